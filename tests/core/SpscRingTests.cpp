#include "hapto/core/SpscRing.h"

#include <catch2/catch.hpp>

#include <cstdint>
#include <thread>
#include <vector>

using namespace hapto;

TEST_CASE("spsc ring: order, capacity rounding, wrap-around") {
    SpscRing<int> ring(5);
    CHECK(ring.capacity() == 8);
    int out = 0;
    CHECK_FALSE(ring.tryPop(out));
    for (int round = 0; round < 10; ++round) {
        for (int i = 0; i < 8; ++i) {
            REQUIRE(ring.tryPush(round * 8 + i));
        }
        REQUIRE_FALSE(ring.tryPush(-1));
        CHECK(ring.sizeApprox() == 8);
        int batch[3];
        REQUIRE(ring.popInto(batch) == 3);
        CHECK(batch[0] == round * 8);
        CHECK(batch[2] == round * 8 + 2);
        for (int i = 3; i < 8; ++i) {
            REQUIRE(ring.tryPop(out));
            REQUIRE(out == round * 8 + i);
        }
        CHECK(ring.sizeApprox() == 0);
    }
}

TEST_CASE("spsc ring: a producer and a consumer thread see every value once, in order",
          "[threads]") {
    SpscRing<std::uint64_t> ring(64);
    constexpr std::uint64_t kCount = 200'000;
    std::thread producer([&] {
        for (std::uint64_t i = 0; i < kCount;) {
            if (ring.tryPush(i)) {
                ++i;
            }
        }
    });
    std::uint64_t expected = 0;
    std::vector<std::uint64_t> batch(16);
    bool inOrder = true;
    while (expected < kCount) {
        const std::size_t n = ring.popInto(batch);
        for (std::size_t i = 0; i < n; ++i) {
            inOrder = inOrder && batch[i] == expected;
            ++expected;
        }
    }
    producer.join();
    CHECK(inOrder);
    std::uint64_t extra = 0;
    CHECK_FALSE(ring.tryPop(extra));
}
