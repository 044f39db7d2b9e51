#include "hapto/runtime/Realtime.h"

#include "hapto/core/Clock.h"
#include "hapto/core/CpuPause.h"

#include <cerrno>
#include <cstring>
#include <ctime>
#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/prctl.h>
#include <unistd.h>
#include <utility>

namespace hapto::rt {
namespace {
thread_local bool tInServoLoop = false;
}

std::uint64_t nowNs() noexcept {
    return monotonicNs();
}

void sleepUntilNs(std::uint64_t deadlineNs, std::uint64_t spinNs) noexcept {
    const std::uint64_t wakeNs = deadlineNs > spinNs ? deadlineNs - spinNs : 0;
    timespec ts;
    ts.tv_sec = static_cast<time_t>(wakeNs / 1'000'000'000ull);
    ts.tv_nsec = static_cast<long>(wakeNs % 1'000'000'000ull);
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
    if (spinNs > 0) {
        while (nowNs() < deadlineNs) {
            cpuPause();
        }
    }
}

void tightenTimerSlack() noexcept {
    // The kernel lets a normal thread's timed sleep end up to 50 us late (timer slack); a
    // servo thread wants its deadline, so ask for 1 ns.
    prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
}

void nameCurrentThread(const char* name) noexcept {
    char shortName[16] = {};
    std::strncpy(shortName, name, sizeof shortName - 1); // the kernel's limit, with the NUL
    (void)pthread_setname_np(pthread_self(), shortName);
}

RealtimeGrant makeCurrentThreadRealtime(int priority, int cpu) {
    RealtimeGrant g;
    tightenTimerSlack();
    sched_param p{};
    p.sched_priority = priority;
    if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p); e == 0) {
        g.fifo = true;
    } else {
        g.note = std::string("SCHED_FIFO refused (") + std::strerror(e) +
                 "): run as root, or grant CAP_SYS_NICE / an rtprio limit; running with normal "
                 "scheduling";
    }
    if (cpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(cpu, &set);
        if (const int e = pthread_setaffinity_np(pthread_self(), sizeof set, &set); e == 0) {
            g.pinned = true;
        } else {
            g.note += (g.note.empty() ? "" : "; ") + std::string("CPU affinity refused (") +
                      std::strerror(e) + ")";
        }
    }
    return g;
}

WakeLatencyHold::WakeLatencyHold(std::int32_t us, std::string_view path) : mUs(us) {
    const std::string file(path);
    if (us < 0) {
        mNote = file + ": a wake-up latency is at least 0 us, not " + std::to_string(us);
        return;
    }
    const int fd = ::open(file.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) {
        mNote = file + ": " + std::strerror(errno) +
                "; idle CPUs keep their usual wake-up latency (run as root to hold it)";
        return;
    }
    // The request is the binary s32 itself (the interface also takes a "0x%08x" string).
    if (::write(fd, &us, sizeof us) != static_cast<ssize_t>(sizeof us)) {
        mNote = file + ": writing " + std::to_string(us) + " us failed: " + std::strerror(errno);
        ::close(fd);
        return;
    }
    mFd = fd;
}

WakeLatencyHold::~WakeLatencyHold() {
    if (mFd >= 0) {
        ::close(mFd); // the kernel drops the request
    }
}

WakeLatencyHold::WakeLatencyHold(WakeLatencyHold&& other) noexcept
    : mFd(std::exchange(other.mFd, -1)), mUs(other.mUs), mNote(std::move(other.mNote)) {}

WakeLatencyHold& WakeLatencyHold::operator=(WakeLatencyHold&& other) noexcept {
    if (this != &other) {
        if (mFd >= 0) {
            ::close(mFd);
        }
        mFd = std::exchange(other.mFd, -1);
        mUs = other.mUs;
        mNote = std::move(other.mNote);
    }
    return *this;
}

bool inServoLoop() noexcept {
    return tInServoLoop;
}
void setInServoLoop(bool inside) noexcept {
    tInServoLoop = inside;
}

} // namespace hapto::rt
