// Linked into each test binary marked ONE_THREAD (tests/CMakeLists.txt): CatchMain.cpp's thread
// check then fails any case of the binary that starts a thread.
extern "C" const bool hapto_test_one_thread = true;
