#include "hapto/core/Geometry.h"
#include "hapto/core/Mailbox.h"

#include <catch2/catch.hpp>

#include <atomic>
#include <cstdint>
#include <thread>
#include <type_traits>

using namespace hapto;

namespace {

/// A payload of several words whose fields all carry the same counter: a torn read shows.
struct Payload {
    Vec3 a{0.0};
    Vec3 b{0.0};
    std::uint64_t n = 0;
};
static_assert(std::is_trivially_copyable_v<Payload>);

Payload payload(std::uint64_t n) {
    const double d = static_cast<double>(n);
    return {Vec3(d, d + 1, d + 2), Vec3(-d), n};
}

bool consistent(const Payload& p) {
    const double d = static_cast<double>(p.n);
    return p.a == Vec3(d, d + 1, d + 2) && p.b == Vec3(-d);
}

} // namespace

TEST_CASE("mailbox: nothing to read before the first publish, then the newest value") {
    Mailbox<Payload> box;
    Payload out = payload(99);
    CHECK_FALSE(box.read(out));
    CHECK(out.n == 99); // untouched
    box.publish(payload(1));
    box.publish(payload(2));
    std::uint64_t writes = 0;
    REQUIRE(box.read(out, writes));
    CHECK(out.n == 2);
    CHECK(consistent(out));
    CHECK(writes == 2);
    box.reset();
    CHECK_FALSE(box.read(out));
}

TEST_CASE("mailbox: a reader racing a writer never sees a torn value, and never goes back",
          "[threads]") {
    Mailbox<Payload> box;
    std::atomic<bool> done{false};
    constexpr std::uint64_t kCount = 100'000;
    std::thread writer([&] {
        for (std::uint64_t i = 1; i <= kCount; ++i) {
            box.publish(payload(i));
        }
        done.store(true);
    });
    bool allConsistent = true;
    bool monotonic = true;
    std::uint64_t last = 0;
    while (!done.load()) {
        Payload p;
        std::uint64_t writes = 0;
        if (box.read(p, writes)) {
            allConsistent = allConsistent && consistent(p) && writes == p.n;
            monotonic = monotonic && p.n >= last;
            last = p.n;
        }
    }
    writer.join();
    CHECK(allConsistent);
    CHECK(monotonic);
    Payload p;
    REQUIRE(box.read(p));
    CHECK(p.n == kCount);
}
