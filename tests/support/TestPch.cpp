// Builds the test sources' precompiled header (Catch2 2.x is one 17,000-line header every test
// source includes); tests/CMakeLists.txt reuses it in every test binary. Nothing else here.
