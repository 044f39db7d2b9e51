#include "hapto/core/SweptShapes.h"

#include <catch2/catch.hpp>

#include <random>

using namespace hapto;

namespace {

constexpr double kSkin = 0.1;
constexpr double kShrink = 0.01;

/// The unit right triangle in z = 0, counter-clockwise seen from +z (its front).
const TriangleCorners kSweptTri{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
const Vec3 kSweptUp(0, 0, 1);

/// The triangle's front test over a path, counting the corner reads.
SweptEntry sweepTri(const Vec3& from, const Vec3& to, int* fetched = nullptr) {
    return sweepTriangleFront(
        kSweptUp, 0.0,
        [&] {
            if (fetched) {
                ++*fetched;
            }
            return TriangleGeometry{kSweptTri, triangleEdges(kSweptTri, kSweptUp)};
        },
        from, to, kSkin, kShrink, 1e-9);
}

} // namespace

TEST_CASE("swept box: a path into a face hits the shrunk skin at the expected fraction") {
    const Vec3 half(1.0, 2.0, 3.0);
    // Along +x into the -x face: the shrunk skin at x = -1.09, the skin at x = -1.1.
    const SweptEntry e = sweepBoxLocal(half, Vec3(-2, 0.5, 0.5), Vec3(2, 0, 0), kSkin, kShrink);
    REQUIRE(e.found);
    CHECK(e.t == Approx((2.0 - 1.09) / 2.0));
    CHECK(e.tStop == Approx((2.0 - 1.1) / 2.0));
    CHECK(e.axis == 0);
    CHECK(e.sign == -1.0);
    // Down into the +z face, obliquely.
    const SweptEntry down = sweepBoxLocal(half, Vec3(0, 0, 5), Vec3(0.5, -0.5, -4), kSkin, kShrink);
    REQUIRE(down.found);
    CHECK(down.t == Approx((5.0 - 3.09) / 4.0));
    CHECK(down.axis == 2);
    CHECK(down.sign == 1.0);
}

TEST_CASE("swept box: no entry from inside, short of it, beside it or parallel to a face") {
    const Vec3 half(1.0, 1.0, 1.0);
    CHECK_FALSE(sweepBoxLocal(half, Vec3(0.5, 0, 0), Vec3(3, 0, 0), kSkin, kShrink).found);
    CHECK_FALSE(sweepBoxLocal(half, Vec3(-3, 0, 0), Vec3(1.5, 0, 0), kSkin, kShrink).found);
    CHECK_FALSE(sweepBoxLocal(half, Vec3(-3, 1.5, 0), Vec3(6, 0, 0), kSkin, kShrink).found);
    // Along the skin of the +y face (inside the skin, outside the shrunk one): passes.
    CHECK_FALSE(sweepBoxLocal(half, Vec3(-3, 1.095, 0), Vec3(6, 0, 0), kSkin, kShrink).found);
    CHECK_FALSE(sweepBoxLocal(half, Vec3(0, 0, 0), Vec3(0, 0, 0), kSkin, kShrink).found);
}

TEST_CASE("swept box: the entry is on the shrunk skin and the way before it outside") {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-3.0, 3.0);
    const Obb box{Vec3(0.0), Vec3(1.0, 0.5, 0.25), Mat3(1.0)};
    int hits = 0;
    for (int n = 0; n < 2000; ++n) {
        const Vec3 a(u(rng), u(rng), u(rng));
        const Vec3 aim(u(rng) / 2.0, u(rng) / 4.0, u(rng) / 8.0); // paths aimed near the box
        const Vec3 d = (1.0 + (u(rng) + 3.0) / 6.0) * (aim - a);
        const SweptEntry e = sweepBoxLocal(box.halfExtents, a, d, kSkin, kShrink);
        if (!e.found) {
            continue;
        }
        ++hits;
        INFO("case " << n);
        REQUIRE(e.t >= 0.0);
        REQUIRE(e.t < 1.0);
        REQUIRE(e.tStop <= e.t);
        REQUIRE(boxSignedDistance(box, a + e.t * d, kSkin - kShrink) == Approx(0.0).margin(1e-9));
        REQUIRE(boxSignedDistance(box, a + e.tStop * d, kSkin) >= -1e-9);
        for (int k = 0; k < 10; ++k) {
            REQUIRE(boxSignedDistance(box, a + (e.t * k / 10.0) * d, kSkin - kShrink) > 0.0);
        }
    }
    CHECK(hits > 1000);
}

TEST_CASE("swept sphere: hits at the expected fraction, and not from inside or away") {
    const SweptEntry e = sweepSphere(Vec3(0.0), 1.0, Vec3(0, 0, -3), Vec3(0, 0, 1), kSkin, kShrink);
    REQUIRE(e.found);
    CHECK(e.t == Approx((3.0 - 1.09) / 4.0));
    CHECK(e.tStop == Approx((3.0 - 1.1) / 4.0));
    CHECK(e.axis == -1);
    // Starting between the skin and the shrunk skin: stops where it is.
    const SweptEntry onSkin =
        sweepSphere(Vec3(0.0), 1.0, Vec3(0, 0, -1.095), Vec3(0, 0, 1), kSkin, kShrink);
    REQUIRE(onSkin.found);
    CHECK(onSkin.tStop == 0.0);
    CHECK_FALSE(sweepSphere(Vec3(0.0), 1.0, Vec3(0, 0, -0.5), Vec3(0, 0, 3), kSkin, kShrink).found);
    CHECK_FALSE(sweepSphere(Vec3(0.0), 1.0, Vec3(0, 0, -3), Vec3(0, 0, -5), kSkin, kShrink).found);
    CHECK_FALSE(
        sweepSphere(Vec3(0.0), 1.0, Vec3(-3, 1.2, 0), Vec3(3, 1.2, 0), kSkin, kShrink).found);
    CHECK_FALSE(sweepSphere(Vec3(0.0), 1.0, Vec3(0, 0, -3), Vec3(0, 0, -2), kSkin, kShrink).found);
    CHECK_FALSE(sweepSphere(Vec3(0.0), 1.0, Vec3(0, 0, -3), Vec3(0, 0, -3), kSkin, kShrink).found);
}

TEST_CASE("swept triangle: from the front only, over the triangle grown by the skin") {
    int fetched = 0;
    const SweptEntry e = sweepTri(Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, -1), &fetched);
    REQUIRE(e.found);
    CHECK(e.t == Approx((1.0 - 0.09) / 2.0));
    CHECK(e.tStop == Approx((1.0 - 0.1) / 2.0));
    CHECK(fetched == 1);
    // From behind, or not going deeper: passes, without reading the corners.
    CHECK_FALSE(sweepTri(Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), &fetched).found);
    CHECK_FALSE(sweepTri(Vec3(0.2, 0.2, 1), Vec3(0.5, 0.5, 1), &fetched).found);
    CHECK_FALSE(sweepTri(Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, 0.5), &fetched).found);
    CHECK(fetched == 1);
    // Beside an edge: within the skin it is stopped (a box face's skin), beyond it passes.
    CHECK(sweepTri(Vec3(-0.05, 0.5, 1), Vec3(-0.05, 0.5, -1)).found);
    CHECK_FALSE(sweepTri(Vec3(-0.15, 0.5, 1), Vec3(-0.15, 0.5, -1)).found);
}

TEST_CASE("swept triangle: a path that crosses the triangle itself is always stopped") {
    // Nearly along the plane: where it enters the skin slab it is far beside the triangle, but
    // it crosses the triangle at (0.25, 0.25, 0).
    const Vec3 from(-10.0, 0.25, 0.1);
    const Vec3 to(0.5, 0.25, -0.1 / 41.0); // crosses z = 0 at x = 0.25
    const SweptEntry e = sweepTri(from, to);
    REQUIRE(e.found);
    const Vec3 entry = from + e.t * (to - from);
    CHECK(entry.z == Approx(kSkin - kShrink));
    CHECK(entry.x < -1.0);
    // The same path ending above the plane does not cross it: it passes.
    CHECK_FALSE(sweepTri(from, Vec3(-3.0, 0.25, 0.05)).found);
}
