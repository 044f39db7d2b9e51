// A preload for the release tests (LD_PRELOAD, set by tests/CMakeLists.txt) that notes every
// thread a process starts: each pthread_create appends one byte to the file named by
// HAPTO_THREAD_PROBE_LOG, when that is set, then starts the thread as usual. Child processes
// inherit both the preload and the variable, so a `hapto` session a test runs is counted too.
// CatchMain.cpp reads the file around each test case to check the case's [threads] tag.
#include <dlfcn.h>
#include <fcntl.h>
#include <pthread.h>
#include <unistd.h>

#include <cstdlib>

namespace {

using CreateThread = int (*)(pthread_t*, const pthread_attr_t*, void* (*)(void*), void*);

constexpr const char* kLogVariable = "HAPTO_THREAD_PROBE_LOG";

} // namespace

extern "C" {

// The variable naming the log; its presence tells CatchMain.cpp that the probe is loaded.
__attribute__((visibility("default"))) const char* hapto_thread_probe_variable() {
    return kLogVariable;
}

__attribute__((visibility("default"))) int pthread_create(pthread_t* thread,
                                                          const pthread_attr_t* attributes,
                                                          void* (*start)(void*), void* argument) {
    static const auto next = reinterpret_cast<CreateThread>(dlsym(RTLD_NEXT, "pthread_create"));
    if (const char* path = std::getenv(kLogVariable)) {
        const int fd = open(path, O_WRONLY | O_APPEND | O_CLOEXEC);
        if (fd >= 0) {
            [[maybe_unused]] const ssize_t written = write(fd, "t", 1);
            close(fd);
        }
    }
    return next(thread, attributes, start, argument);
}

} // extern "C"
