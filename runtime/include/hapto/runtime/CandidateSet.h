#pragma once
/// The few spans of object slots a renderer may look at in one servo tick (no copies).

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace hapto {

/// Up to sixteen spans of candidate items (object slots and triangle items of `scene`): the
/// device point's leaf, the proxy's leaf, the snapshot's moving objects, and up to thirteen
/// leaves the proxy slid into during the tick (HapticTick solves again with them). The spans
/// are views; whoever fills the set keeps the storage alive for the tick. Slots may repeat
/// across (and within) spans: the renderer treats duplicates as one object.
struct CandidateSet {
    /// How many spans fit.
    static constexpr std::size_t kMaxSpans = 16;

    std::array<std::span<const std::uint32_t>, kMaxSpans>
        spans{};             ///< The spans; first `count` used.
    std::uint8_t count = 0;  ///< Spans in use.
    bool overflowed = false; ///< True when add() was called on a full set (that span was dropped).

    /// Appends a span; returns false (and sets `overflowed`) when all of them are in use. Empty
    /// spans are accepted and cost nothing. [servo]
    bool add(std::span<const std::uint32_t> slots) noexcept {
        if (count >= kMaxSpans) {
            overflowed = true;
            return false;
        }
        spans[count++] = slots;
        return true;
    }
    /// Forgets every span. [servo]
    void clear() noexcept {
        spans = {};
        count = 0;
        overflowed = false;
    }
    /// The number of slots over all spans, duplicates included. [servo]
    std::size_t totalSize() const noexcept {
        std::size_t n = 0;
        for (std::size_t i = 0; i < count; ++i) {
            n += spans[i].size();
        }
        return n;
    }
};

} // namespace hapto
