#pragma once
// Replaces the global operator new and delete (every form: plain, array, nothrow, over-aligned)
// with ones that count each allocation, for the test binaries that prove a path never
// allocates. Include it in exactly one source file of a test binary of its own: the
// replacement is program-wide.
//
// `hapto::test::gAllocations` counts every allocation; `gFlaggedAllocations` counts those made
// while `gFlagAllocation` (if set) returns true, e.g. inside a servo loop.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

namespace hapto::test {

inline std::atomic<std::uint64_t> gAllocations{0};
inline std::atomic<std::uint64_t> gFlaggedAllocations{0};
inline bool (*gFlagAllocation)() noexcept = nullptr;

inline void* countedAllocation(std::size_t n, std::size_t align = 0) noexcept {
    gAllocations.fetch_add(1, std::memory_order_relaxed);
    if (gFlagAllocation != nullptr && gFlagAllocation()) {
        gFlaggedAllocations.fetch_add(1, std::memory_order_relaxed);
    }
    n = n ? n : 1;
    if (align > alignof(std::max_align_t)) {
        return std::aligned_alloc(align, (n + align - 1) / align * align);
    }
    return std::malloc(n);
}

inline void* countedAllocationOrThrow(std::size_t n, std::size_t align = 0) {
    if (void* p = countedAllocation(n, align)) {
        return p;
    }
    throw std::bad_alloc();
}

} // namespace hapto::test

void* operator new(std::size_t n) {
    return hapto::test::countedAllocationOrThrow(n);
}
void* operator new[](std::size_t n) {
    return hapto::test::countedAllocationOrThrow(n);
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
    return hapto::test::countedAllocation(n);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
    return hapto::test::countedAllocation(n);
}
void* operator new(std::size_t n, std::align_val_t a) {
    return hapto::test::countedAllocationOrThrow(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a) {
    return hapto::test::countedAllocationOrThrow(n, static_cast<std::size_t>(a));
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
    return hapto::test::countedAllocation(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
    return hapto::test::countedAllocation(n, static_cast<std::size_t>(a));
}
void operator delete(void* p) noexcept {
    std::free(p);
}
void operator delete[](void* p) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
    std::free(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
    std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
    std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
    std::free(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
    std::free(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
    std::free(p);
}
