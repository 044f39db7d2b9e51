// Build and run: g++ -O2 -o floor floor.cpp && ./floor && ./floor hot   (docs/results/tick.md)
// The machine's floor: a fixed ~0.8 us piece of work timed after a 1 ms sleep, as a servo tick is.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <vector>
static std::uint64_t now() {
    timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1000000000ull + t.tv_nsec;
}
int main(int argc, char** argv) {
    const bool sleepFirst = argc < 2 || argv[1][0] != 'h';
    std::vector<double> buf(2048, 1.0); // 16 kB touched per tick
    std::vector<std::uint64_t> ns;
    volatile double sink = 0;
    timespec next;
    clock_gettime(CLOCK_MONOTONIC, &next);
    for (int i = 0; i < 5000; ++i) {
        if (sleepFirst) {
            next.tv_nsec += 1000000;
            if (next.tv_nsec >= 1000000000) {
                next.tv_nsec -= 1000000000;
                ++next.tv_sec;
            }
            clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
        }
        const std::uint64_t t0 = now();
        double s = 0;
        for (int k = 0; k < 2048; k += 8)
            s += buf[k] * buf[(k * 7) & 2047];
        for (int r = 0; r < 120; ++r)
            s = s * 1.0000001 + 0.5;
        sink = sink + s;
        ns.push_back(now() - t0);
    }
    std::sort(ns.begin(), ns.end());
    auto q = [&](double f) { return ns[std::min(ns.size() - 1, std::size_t(f * ns.size()))]; };
    std::printf("%s: p50 %llu ns, p99 %llu ns, p99.9 %llu ns, max %llu ns\n",
                sleepFirst ? "after 1 ms sleep" : "back to back", (unsigned long long)q(0.5),
                (unsigned long long)q(0.99), (unsigned long long)q(0.999),
                (unsigned long long)ns.back());
}
