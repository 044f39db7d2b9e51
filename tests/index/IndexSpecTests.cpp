#include "hapto/index/IndexSpec.h"
#include "hapto/io/InputError.h"

#include <catch2/catch.hpp>

using namespace hapto;

TEST_CASE("index specs parse and round-trip") {
    CHECK(IndexSpec::parse("brute") == IndexSpec::brute());
    CHECK(IndexSpec::parse("grid:5") == IndexSpec::grid(5));
    CHECK(IndexSpec::parse("grid:5:aabb") == IndexSpec::grid(5, OverlapMode::Aabb));
    CHECK(IndexSpec::parse("octree:2:0.005") == IndexSpec::octree(2, 0.005));
    CHECK(IndexSpec::parse("octree:5:0.005:aabb") ==
          IndexSpec::octree(5, 0.005, OverlapMode::Aabb));
    CHECK(IndexSpec::parse("octree:2:5e-3:obb") == IndexSpec::octree(2, 0.005));
    for (const char* text : {"brute", "brute:aabb", "grid:1", "grid:256:aabb", "octree:2:0.005",
                             "octree:1:0.0001:aabb", "octree:64:0.1234567890123"}) {
        CAPTURE(text);
        CHECK(IndexSpec::parse(text).toString() == text);
        CHECK(IndexSpec::parse(IndexSpec::parse(text).toString()) == IndexSpec::parse(text));
    }
}

TEST_CASE("bad index specs are refused with a message saying what is expected") {
    for (const char* text :
         {"", "grid", "grid:0", "grid:257", "grid:5.5", "grid:x", "octree:2", "octree:0:0.005",
          "octree:2:0", "octree:2:-1", "octree:2:nan", "octree:2:inf", "octree:2:0.005:obb:aabb",
          "tree:2", "brute:5", "grid:5:aabbx", "GRID:5"}) {
        CAPTURE(text);
        CHECK_THROWS_AS(IndexSpec::parse(text), InputError);
    }
    CHECK_THROWS_WITH(IndexSpec::parse("grid:0"),
                      Catch::Contains("grid:0") && Catch::Contains("1 to 256"));
    CHECK_THROWS_WITH(IndexSpec::parse("octree:2:x"), Catch::Contains("metres"));
    CHECK_THROWS_WITH(IndexSpec::parse("kd"), Catch::Contains("octree:M:MIN"));
}

TEST_CASE("a parsed spec carries the default memory limit, 1024 MB") {
    CHECK(IndexSpec::kDefaultMaxBytes == 1024ull * 1024 * 1024);
    CHECK(IndexSpec::parse("grid:5").maxBytes == IndexSpec::kDefaultMaxBytes);
    CHECK(IndexSpec::octree(2, 0.005).maxBytes == IndexSpec::kDefaultMaxBytes);
    IndexSpec limited = IndexSpec::grid(5);
    limited.maxBytes = 1;
    CHECK(limited.toString() == "grid:5"); // not part of the text form
    CHECK(IndexSpec::grid(5).withMaxMegabytes(3).maxBytes == 3u << 20);
    CHECK(IndexSpec::grid(5).withMaxMegabytes(~std::uint64_t(0)).maxBytes == ~std::uint64_t(0));
}
