#pragma once
/// A build's scratch array (internal): exact size, uninitialised, freed before it is reallocated.

#include <cstddef>
#include <memory>
#include <type_traits>
#include <utility>

namespace hapto::detail {

/// A build's scratch array, allocated at its exact size and left uninitialised: every step
/// writes each element it later reads, so nothing is zeroed serially before a parallel fill,
/// and the pages are first touched (a page fault each, a large part of a build's time on the
/// 2-core VM) by the threads that fill them. Only for types whose objects begin to live with
/// their storage (scalars, aggregates) and need no destructor. reset() frees the old array
/// first, so the two are never held at once. [control]
template <class T> class ScratchArray {
    static_assert(std::is_trivially_destructible_v<T> &&
                  (std::is_scalar_v<T> || std::is_aggregate_v<T>));

public:
    ScratchArray() = default;
    ScratchArray(const ScratchArray&) = delete;
    ScratchArray& operator=(const ScratchArray&) = delete;
    ~ScratchArray() { reset(0); }
    void reset(std::size_t size) {
        if (mData != nullptr) {
            std::allocator<T>().deallocate(mData, mSize);
        }
        mData = nullptr;
        mSize = 0;
        if (size > 0) {
            mData = std::allocator<T>().allocate(size);
            mSize = size;
        }
    }
    std::size_t size() const noexcept { return mSize; }
    T& operator[](std::size_t i) noexcept { return mData[i]; }
    const T& operator[](std::size_t i) const noexcept { return mData[i]; }
    T* begin() noexcept { return mData; }
    T* end() noexcept { return mData + mSize; }
    void swap(ScratchArray& other) noexcept {
        std::swap(mData, other.mData);
        std::swap(mSize, other.mSize);
    }

private:
    T* mData = nullptr;
    std::size_t mSize = 0;
};
} // namespace hapto::detail
