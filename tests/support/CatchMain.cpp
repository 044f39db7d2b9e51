// The one Catch2 main shared by every test binary, with the check that keeps the ThreadSanitizer
// build's test set whole. That build (HAPTO_TEST_SET threads) runs only the cases tagged
// [threads] or [realtime], and leaves out the binaries marked ONE_THREAD. In the release tests
// the preload ThreadProbe.cpp notes every thread a process starts, including in the processes
// the case runs; a case that started one fails here unless it carries one of those tags, and in
// a ONE_THREAD binary any case that starts one fails. Without the preload (a test binary started
// by hand, the sanitizer builds) nothing is checked.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include <dlfcn.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

extern "C" const bool hapto_test_one_thread __attribute__((weak));

namespace {

struct ThreadCheck {
    std::string log;                   // the probe's log; empty when the probe is not loaded
    off_t logSizeAtStart = 0;          // the log's size when the running case started
    std::vector<std::string> failures; // one line for each case that broke the rule
};

ThreadCheck& threadCheck() {
    static ThreadCheck check;
    return check;
}

off_t logSize() {
    struct stat status {};
    return stat(threadCheck().log.c_str(), &status) == 0 ? status.st_size : 0;
}

bool hasTag(const Catch::TestCaseInfo& info, const std::string& tag) {
    return std::find(info.lcaseTags.begin(), info.lcaseTags.end(), tag) != info.lcaseTags.end();
}

class ThreadTagListener : public Catch::TestEventListenerBase {
public:
    using TestEventListenerBase::TestEventListenerBase;

    void testCaseStarting(const Catch::TestCaseInfo&) override {
        if (!threadCheck().log.empty())
            threadCheck().logSizeAtStart = logSize();
    }

    void testCaseEnded(const Catch::TestCaseStats& stats) override {
        ThreadCheck& check = threadCheck();
        if (check.log.empty() || logSize() == check.logSizeAtStart)
            return;
        const Catch::TestCaseInfo& info = stats.testInfo;
        if (&hapto_test_one_thread != nullptr)
            check.failures.push_back("'" + info.name +
                                     "' starts a thread, but its binary is marked "
                                     "ONE_THREAD (tests/CMakeLists.txt): drop the mark and tag the "
                                     "case [threads]");
        else if (!hasTag(info, "threads") && !hasTag(info, "realtime"))
            check.failures.push_back("'" + info.name +
                                     "' starts a thread (here or in a process it "
                                     "runs) but is not tagged [threads]: the ThreadSanitizer build "
                                     "runs only [threads] and [realtime] cases");
    }
};

CATCH_REGISTER_LISTENER(ThreadTagListener)

// With the probe loaded, makes its log (inherited by every process a case starts).
void startThreadCheck() {
    using Variable = const char* (*)();
    const auto variable =
        reinterpret_cast<Variable>(dlsym(RTLD_DEFAULT, "hapto_thread_probe_variable"));
    if (variable == nullptr)
        return;
    const char* tmp = std::getenv("TMPDIR");
    std::string path =
        std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/hapto-thread-probe.XXXXXX";
    const int fd = mkstemp(path.data());
    if (fd < 0) {
        std::fprintf(stderr, "thread check: cannot create %s\n", path.c_str());
        std::exit(1);
    }
    close(fd);
    setenv(variable(), path.c_str(), 1);
    threadCheck().log = path;
}

// Removes the log; prints each case that broke the rule and returns whether none did.
bool finishThreadCheck() {
    ThreadCheck& check = threadCheck();
    if (!check.log.empty())
        unlink(check.log.c_str());
    for (const std::string& failure : check.failures)
        std::fprintf(stderr, "thread check: %s\n", failure.c_str());
    return check.failures.empty();
}

} // namespace

int main(int argc, char** argv) {
    startThreadCheck();
    const int result = Catch::Session().run(argc, argv);
    return finishThreadCheck() ? result : 1;
}
