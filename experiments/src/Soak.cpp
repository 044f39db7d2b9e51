// `hapto soak` as a library: D simulated hands for a while over a world that keeps changing,
// with faults injected on a schedule. Reports, per window, each device's tick rate and its
// drift from the nominal rate, missed deadlines and the process's resident memory; at the end,
// whether every injected fault zeroed its device and the device came back, and whether memory
// stayed flat.

#include "hapto/experiments/Soak.h"

#include "hapto/experiments/ExperimentSupport.h"
#include "hapto/experiments/Table.h"

#include "hapto/core/Random.h"
#include "hapto/devices/DeviceFactory.h"
#include "hapto/devices/FaultInjectingDevice.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/Session.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <unistd.h>

namespace hapto::experiments {

double slopePerHour(const std::vector<double>& xS, const std::vector<double>& y) {
    const std::size_t n = xS.size();
    if (n < 2) {
        return 0.0;
    }
    double mx = 0, my = 0;
    for (std::size_t i = 0; i < n; ++i) {
        mx += xS[i];
        my += y[i];
    }
    mx /= static_cast<double>(n);
    my /= static_cast<double>(n);
    double sxy = 0, sxx = 0;
    for (std::size_t i = 0; i < n; ++i) {
        sxy += (xS[i] - mx) * (y[i] - my);
        sxx += (xS[i] - mx) * (xS[i] - mx);
    }
    return sxx > 0 ? 3600.0 * sxy / sxx : 0.0;
}

namespace {

// The faults, injected in turn into device k % D. Stalls shorter than the watchdog only cost
// deadlines; longer ones are faults.
struct FaultPlan {
    InjectedFault kind;
    double durationWatchdogs; // duration in units of the watchdog timeout (stalls)
    double durationS;         // fixed duration (disconnect)
    bool isFault;             // the runtime must fault, zero and reopen the device
    const char* label;
};
constexpr FaultPlan kFaultPlans[] = {
    {InjectedFault::Disconnect, 0.0, 0.5, true, "disconnect for 0.5 s"},
    {InjectedFault::Stall, 0.4, 0.0, false, "stall for 0.4 watchdog timeouts"},
    {InjectedFault::Garbage, 0.0, 0.0, true, "non-finite sample"},
    {InjectedFault::Stall, 3.0, 0.0, true, "stall for 3 watchdog timeouts"},
    {InjectedFault::ReadError, 0.0, 0.0, true, "read error"},
};

double residentMiB() {
    std::ifstream statm("/proc/self/statm");
    double pages = 0, resident = 0;
    statm >> pages >> resident;
    return resident * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

struct DeviceWindow {
    double rateHz = 0, driftPpm = 0;
    std::uint64_t ticks = 0, missed = 0, faults = 0;
    double downS = 0;
};

struct Window {
    double endS = 0, rssMiB = 0;
    std::vector<DeviceWindow> devices;
};

struct DeviceTally {
    std::uint64_t injected = 0, expectedFaults = 0;
};

// The world keeps changing: one sphere circles the origin for 2 s of every 5 (moves at 100 Hz,
// then rests so the index is rebuilt), and every 10 s a box appears somewhere, gone 5 s later.
class WorldChurn {
public:
    WorldChurn(World& world, const Scene& scene) : mWorld(world), mBounds(scene.bounds()) {
        ObjectId top = 0;
        for (std::uint32_t i = 0; i < scene.size(); ++i) {
            top = std::max(top, scene.object(i).id);
        }
        mMover = top + 1;
        mNextBox = top + 2;
        mWorld.addObject(makeSphere(mMover, Vec3(0.03, 0.0, 0.0), 0.005));
        ++mUpdates;
    }

    void step(double tS) {
        const double phase = std::fmod(tS, 5.0);
        if (phase < 2.0 && tS - mLastMoveS >= 0.01) {
            const double a = tS * 1.5;
            mWorld.moveObject(mMover, Vec3(0.03 * std::cos(a), 0.0, 0.03 * std::sin(a)),
                              Quat(1, 0, 0, 0));
            mLastMoveS = tS;
            ++mUpdates;
        }
        const int cycle = static_cast<int>(tS / 10.0);
        if (cycle != mCycle && std::fmod(tS, 10.0) < 5.0) {
            mCycle = cycle;
            const Vec3 c(mRandom.uniform(mBounds.min.x, mBounds.max.x),
                         mRandom.uniform(mBounds.min.y, mBounds.max.y),
                         mRandom.uniform(mBounds.min.z, mBounds.max.z));
            mBox = mNextBox++;
            mWorld.addObject(makeBox(*mBox, c, Vec3(0.005), Quat(1, 0, 0, 0)));
            ++mUpdates;
        } else if (mBox && std::fmod(tS, 10.0) >= 5.0) {
            mWorld.removeObject(*mBox);
            mBox.reset();
            ++mUpdates;
        }
    }

    std::uint64_t updates() const { return mUpdates; }

private:
    World& mWorld;
    Aabb mBounds;
    ObjectId mMover = 0, mNextBox = 0;
    std::optional<ObjectId> mBox;
    Random mRandom{2026};
    double mLastMoveS = -1.0;
    int mCycle = -1;
    std::uint64_t mUpdates = 0;
};

// The soak's hands: simulated, spread along x in the clear middle of the scene (every other
// one walks the scene), each behind a fault injector (returned in `injectors`).
std::vector<RuntimeDevice> makeHands(const SoakOptions& a, const Scene& scene,
                                     std::vector<FaultInjectingDevice*>& injectors) {
    std::vector<RuntimeDevice> hands;
    for (int i = 0; i < a.devices; ++i) {
        const double x = a.devices == 1 ? 0.0 : -0.02 + 0.04 * i / (a.devices - 1);
        const DeviceConfig c =
            simHand("hand" + std::to_string(i), a.rateHz, i % 2 == 0 ? "slide" : "walk",
                    static_cast<std::uint64_t>(i + 1), Vec3(x, 0, 0));
        auto device = std::make_unique<FaultInjectingDevice>(makeDevice(c, scene));
        injectors.push_back(device.get());
        hands.push_back({std::move(device), c, nullptr});
    }
    return hands;
}

// What a soak records while it runs: the faults it injected, per device, and its windows (each
// device's ticks, rate, drift, misses, faults and time down, and the resident memory), printed
// as each window closes.
class SoakLog {
public:
    SoakLog(const SoakOptions& a, const Runtime& runtime, std::vector<FaultInjectingDevice*> inj)
        : mOptions(a), mRuntime(runtime), mInjectors(std::move(inj)),
          mTally(static_cast<std::size_t>(a.devices)),
          mPrevious(static_cast<std::size_t>(a.devices)), mStartMiB(residentMiB()),
          mPeakMiB(mStartMiB) {}

    // Injects the fault due at `tS`, if one is (none in the quiet tail before the end).
    void injectDue(double tS) {
        if (tS < mOptions.faultEveryS * static_cast<double>(mNextFault + 1) ||
            tS >= mOptions.durationS - soakQuietTailS(mOptions)) {
            return;
        }
        const FaultPlan& plan = kFaultPlans[mNextFault % std::size(kFaultPlans)];
        const std::size_t target = mNextFault % mInjectors.size();
        const double durS = plan.durationS + plan.durationWatchdogs * mOptions.watchdogMs / 1000;
        mInjectors[target]->inject(plan.kind, static_cast<std::uint64_t>(durS * 1e9));
        ++mTally[target].injected;
        mTally[target].expectedFaults += plan.isFault ? 1 : 0;
        ++mNextFault;
    }

    // Closes the window ending at `endS` (session time) and prints its lines.
    void closeWindow(double endS) {
        Window w;
        w.endS = endS;
        w.rssMiB = residentMiB();
        mPeakMiB = std::max(mPeakMiB, w.rssMiB);
        const RunReport r = mRuntime.report();
        for (std::size_t i = 0; i < r.devices.size(); ++i) {
            const DeviceReport& d = r.devices[i];
            DeviceWindow now{0, 0, d.ticks, d.missedDeadlines, d.faults, d.downS};
            DeviceWindow dw = now;
            dw.ticks = now.ticks - mPrevious[i].ticks;
            dw.missed = now.missed - mPrevious[i].missed;
            dw.faults = now.faults - mPrevious[i].faults;
            dw.downS = now.downS - mPrevious[i].downS;
            const double up = (endS - mPreviousEndS) - dw.downS;
            dw.rateHz = up > 0 ? static_cast<double>(dw.ticks) / up : 0.0;
            dw.driftPpm = (dw.rateHz / d.rateHz - 1.0) * 1e6;
            std::printf("%8.1f %-8s %10llu %9.3f %+11.0f %7llu %6llu %7.3f %9.1f\n", endS,
                        d.name.c_str(), static_cast<unsigned long long>(dw.ticks), dw.rateHz,
                        dw.driftPpm, static_cast<unsigned long long>(dw.missed),
                        static_cast<unsigned long long>(dw.faults), dw.downS, w.rssMiB);
            w.devices.push_back(dw);
            mPrevious[i] = now;
        }
        std::fflush(stdout);
        mPreviousEndS = endS;
        mWindows.push_back(std::move(w));
    }

    double previousEndS() const { return mPreviousEndS; }
    const std::vector<Window>& windows() const { return mWindows; }
    const DeviceTally& tally(std::size_t i) const { return mTally[i]; }
    const FaultInjectingDevice& injector(std::size_t i) const { return *mInjectors[i]; }
    std::size_t faultsInjected() const { return mNextFault; }
    double startMiB() const { return mStartMiB; }
    double peakMiB() const { return mPeakMiB; }

private:
    const SoakOptions& mOptions;
    const Runtime& mRuntime;
    std::vector<FaultInjectingDevice*> mInjectors;
    std::vector<DeviceTally> mTally;
    std::vector<Window> mWindows;
    std::vector<DeviceWindow> mPrevious;
    std::size_t mNextFault = 0;
    double mPreviousEndS = 0, mStartMiB = 0, mPeakMiB = 0;
};

// The control steps of a soak: until its duration the world churns, faults are injected and
// windows close; then, for at most 5 s, the last faults may recover. False when that is done.
bool soakStep(double tS, const SoakOptions& a, const Runtime& runtime, WorldChurn& churn,
              SoakLog& log, std::optional<double>& settleFromS) {
    if (tS < a.durationS) {
        churn.step(tS);
        log.injectDue(tS);
        if (tS - log.previousEndS() >= a.windowS) {
            log.closeWindow(tS);
        }
        return true;
    }
    if (!settleFromS) {
        settleFromS = tS;
    }
    const RunReport r = runtime.report();
    const bool recovered = std::all_of(r.devices.begin(), r.devices.end(),
                                       [](const DeviceReport& d) { return d.fault.empty(); });
    return !recovered && tS - *settleFromS < 5.0;
}

// The verdict over the devices: one table per device, declared once (printed as markdown,
// written as the report's JSON), and whether every injected fault went as planned.
struct DeviceVerdict {
    Table table;
    bool faultsOk = true;
    std::uint64_t ticks = 0, missed = 0;
};

DeviceVerdict judgeDevices(const RunReport& r, const SoakLog& log) {
    using experiments::ColumnIn;
    using Int = std::int64_t;
    DeviceVerdict v{Table({
        {"name", "", -1, "device"},
        {"ticks", "", -1, "ticks"},
        {"missed_deadlines", "", -1, "", ColumnIn::Data},
        {"missed_pct", "%", 4, "missed %", ColumnIn::Markdown},
        {"late_wakeups", "", -1, "", ColumnIn::Data},
        {"zeroed_for_misses", "", -1, "zeroed"},
        {"drift_ppm", "ppm", 0, "drift ppm"},
        {"worst_window_drift_ppm", "ppm", 0, "worst window ppm"},
        {"drift_trend_ppm_per_hour", "ppm/h", 0, "drift trend ppm/h"},
        {"faults_injected", "", -1, "", ColumnIn::Data},
        {"faults_expected", "", -1, "faults expected"},
        {"faults", "", -1, "faults seen"},
        {"reopens", "", -1, "reopens"},
        {"down_s", "s", 3, "down s"},
        {"fault", "", -1, "", ColumnIn::Data},
        {"load_p999", "", -1, "", ColumnIn::Data},
        {"load_p999_pct", "%", 2, "p99.9 load %", ColumnIn::Markdown},
        {"lateness_max_ns", "ns", -1, "", ColumnIn::Data},
        {"ok", "", -1, "faults handled"},
    })};
    for (std::size_t i = 0; i < r.devices.size(); ++i) {
        const DeviceReport& d = r.devices[i];
        const DeviceTally& tally = log.tally(i);
        const bool taken = log.injector(i).injected() == tally.injected;
        const bool ok =
            taken && d.fault.empty() && d.faults == tally.expectedFaults && d.reopens == d.faults;
        v.faultsOk = v.faultsOk && ok;
        v.ticks += d.ticks;
        v.missed += d.missedDeadlines;
        double worstDrift = 0;
        std::vector<double> at, drift;
        for (const Window& w : log.windows()) {
            if (std::abs(w.devices[i].driftPpm) > std::abs(worstDrift)) {
                worstDrift = w.devices[i].driftPpm;
            }
            at.push_back(w.endS);
            drift.push_back(w.devices[i].driftPpm);
        }
        const double wholeRate =
            static_cast<double>(d.ticks) / std::max(1e-9, r.durationS - d.downS);
        v.table.add({d.name, Int(d.ticks), Int(d.missedDeadlines),
                     100.0 * static_cast<double>(d.missedDeadlines) /
                         static_cast<double>(std::max<std::uint64_t>(1, d.ticks)),
                     Int(d.lateWakeups), Int(d.zeroedForMisses), (wholeRate / d.rateHz - 1.0) * 1e6,
                     worstDrift, slopePerHour(at, drift), Int(tally.injected),
                     Int(tally.expectedFaults), Int(d.faults), Int(d.reopens), d.downS, d.fault,
                     d.loadFraction.p999, 100.0 * d.loadFraction.p999,
                     static_cast<double>(d.latenessNs.max), ok});
    }
    return v;
}

// Memory: the median of the last third of the windows against the median of the first third,
// the very first window left out (allocators and caches warm up in it). Single windows swing
// by a MiB or two as index rebuilds come and go.
struct MemoryVerdict {
    double baseMiB = 0, endMiB = 0, growthMiB = 0, trendMiBPerHour = 0;
    bool flat = false;
};

MemoryVerdict judgeMemory(const std::vector<Window>& windows, double toleranceMiB) {
    std::vector<double> rss, rssAt;
    for (std::size_t w = windows.size() > 1 ? 1 : 0; w < windows.size(); ++w) {
        rss.push_back(windows[w].rssMiB);
        rssAt.push_back(windows[w].endS);
    }
    const std::size_t third = std::max<std::size_t>(1, rss.size() / 3);
    MemoryVerdict m;
    m.baseMiB =
        median(std::vector<double>(rss.begin(), rss.begin() + static_cast<std::ptrdiff_t>(third)));
    m.endMiB =
        median(std::vector<double>(rss.end() - static_cast<std::ptrdiff_t>(third), rss.end()));
    m.growthMiB = m.endMiB - m.baseMiB;
    m.trendMiBPerHour = slopePerHour(rssAt, rss);
    m.flat = m.growthMiB <= toleranceMiB;
    return m;
}

// The report's "windows": each window's end, memory and per-device figures.
nlohmann::json windowsJson(const std::vector<Window>& windows) {
    nlohmann::json out = nlohmann::json::array();
    for (const Window& w : windows) {
        nlohmann::json per = nlohmann::json::array();
        for (const DeviceWindow& d : w.devices) {
            per.push_back({{"ticks", d.ticks},
                           {"rate_hz", d.rateHz},
                           {"drift_ppm", d.driftPpm},
                           {"missed", d.missed},
                           {"faults", d.faults},
                           {"down_s", d.downS}});
        }
        out.push_back({{"end_s", w.endS}, {"rss_mib", w.rssMiB}, {"devices", per}});
    }
    return out;
}

// Everything a soak ends with, for its verdict lines and its report.
struct SoakOutcome {
    const SoakOptions& options;
    const IndexSpec& spec;
    const Scene& scene;
    const World& world;
    const WorldChurn& churn;
    const SoakLog& log;
    const RunReport& report;
    bool interrupted = false;
};

// Prints the verdict and writes the JSON report when asked for; returns the exit code.
int concludeSoak(const SoakOutcome& o) {
    const SoakOptions& a = o.options;
    const RunReport& r = o.report;
    const DeviceVerdict devices = judgeDevices(r, o.log);
    std::printf("\n%s", devices.table.markdown().c_str());
    const MemoryVerdict memory = judgeMemory(o.log.windows(), a.memoryToleranceMiB);
    const std::size_t faults = o.log.faultsInjected();
    const double missedPct = 100.0 * static_cast<double>(devices.missed) /
                             static_cast<double>(std::max<std::uint64_t>(1, devices.ticks));
    std::printf("memory: %.1f MiB at start; median %.1f MiB over the first third of the windows, "
                "%.1f MiB over the last third (peak %.1f): growth %+.2f MiB, trend %+.2f MiB/h "
                "-> %s\n",
                o.log.startMiB(), memory.baseMiB, memory.endMiB, o.log.peakMiB(), memory.growthMiB,
                memory.trendMiBPerHour, memory.flat ? "flat" : "GROWING");
    std::printf("world: %llu updates published, %llu index rebuilds, %zu snapshots left unfreed\n",
                static_cast<unsigned long long>(o.churn.updates()),
                static_cast<unsigned long long>(o.world.buildsPublished()), o.world.retiredCount());
    std::printf("faults: %zu injected; %s\n", faults,
                !devices.faultsOk ? "NOT handled as expected (see above)"
                : faults == 0     ? "none, so fault handling was not tested"
                                  : "every one zeroed its device at once and the device came "
                                    "back, no other faults");
    // Stopped by a signal, or no fault injected (a machine too slow to reach the first one):
    // then nothing was tested to the end, and the soak cannot pass.
    const bool pass = devices.faultsOk && memory.flat && faults > 0 && !o.interrupted;
    std::printf("timing: %.4f %% of deadlines missed (DESIGN's verdict: <= 0.1 %%: %s)%s\n",
                missedPct, missedPct <= 0.1 ? "met" : "not met",
                r.realtimeNote.empty() ? "" : ("; note: " + r.realtimeNote).c_str());
    if (!a.report.empty()) {
        nlohmann::json perDevice = nlohmann::json::array();
        for (std::size_t i = 0; i < r.devices.size(); ++i) {
            nlohmann::json device = devices.table.json(i);
            device["events"] = r.devices[i].events;
            perDevice.push_back(device);
        }
        const nlohmann::json out{{"settings",
                                  {{"minutes", a.durationS / 60.0},
                                   {"duration_s", a.durationS},
                                   {"devices", a.devices},
                                   {"rate_hz", a.rateHz},
                                   {"index", o.spec.toString()},
                                   {"objects", o.scene.size()},
                                   {"fault_every_s", a.faultEveryS},
                                   {"window_s", a.windowS},
                                   {"watchdog_ms", a.watchdogMs},
                                   {"reopen_ms", a.reopenMs},
                                   {"realtime", a.realtime}}},
                                 {"duration_s", r.durationS},
                                 {"devices", perDevice},
                                 {"windows", windowsJson(o.log.windows())},
                                 {"memory",
                                  {{"start_mib", o.log.startMiB()},
                                   {"base_mib", memory.baseMiB},
                                   {"end_mib", memory.endMiB},
                                   {"trend_mib_per_hour", memory.trendMiBPerHour},
                                   {"peak_mib", o.log.peakMiB()},
                                   {"growth_mib", memory.growthMiB},
                                   {"flat", memory.flat}}},
                                 {"world",
                                  {{"updates", o.churn.updates()},
                                   {"rebuilds", o.world.buildsPublished()},
                                   {"unfreed_snapshots", o.world.retiredCount()}}},
                                 {"faults_injected", faults},
                                 {"faults_ok", devices.faultsOk},
                                 {"missed_pct", missedPct},
                                 {"interrupted", o.interrupted},
                                 {"pass", pass}};
        writeFileAtomically(a.report, out.dump(2) + "\n");
        std::fprintf(stderr, "report written to %s\n", a.report.c_str());
    }
    if (o.interrupted) {
        std::printf("soak: INTERRUPTED after %.1f of %.1f s: no verdict\n", r.durationS,
                    a.durationS);
    } else {
        std::printf("soak: %s\n", pass ? "PASS" : "FAIL");
    }
    return pass ? 0 : 1;
}

} // namespace

double soakQuietTailS(const SoakOptions& a) {
    return std::min(a.durationS / 2, 3.0 * a.watchdogMs / 1000 + 1.0 + a.reopenMs / 1000);
}

void checkSoakOptions(const SoakOptions& a) {
    const double durationS = a.durationS;
    const double quietTailS = soakQuietTailS(a);
    if (a.faultEveryS >= durationS - quietTailS) {
        char text[320];
        std::snprintf(text, sizeof text,
                      "%s: a soak of %g s would end before its first fault (--fault-every "
                      "%g s; faults stop %.1f s before the end so the last can recover), so it "
                      "could test nothing; run longer or inject faults more often",
                      a.durationOption.c_str(), durationS, a.faultEveryS, quietTailS);
        throw InputError(text);
    }
}

int runSoak(std::shared_ptr<const Scene> shared, const SoakOptions& a, const SoakControl& control) {
    const Scene& scene = *shared;
    checkSoakOptions(a);
    const IndexSpec spec = IndexSpec::parse(a.index).withMaxMegabytes(a.maxIndexMb);
    World world(shared, spec);
    std::vector<FaultInjectingDevice*> injectors;
    RuntimeOptions opt;
    opt.realtime = a.realtime;
    opt.stallTimeoutNs = static_cast<std::uint64_t>(a.watchdogMs * 1e6);
    opt.reopenAfterNs = static_cast<std::uint64_t>(a.reopenMs * 1e6);
    Runtime runtime(world, makeHands(a, scene, injectors), opt);
    if (control.onRuntime) {
        control.onRuntime(runtime);
    }

    std::fprintf(stderr,
                 "hapto soak: %d devices at %.0f Hz, %u objects, index %s, %.1f min; a fault "
                 "every %.1f s, windows of %.0f s\n",
                 a.devices, a.rateHz, scene.size(), spec.toString().c_str(), a.durationS / 60.0,
                 a.faultEveryS, a.windowS);
    SessionOptions options; // the soak ends itself (soakStep): no duration here
    options.controlPeriodNs = 2'000'000;
    options.stopRequested = control.stopRequested;
    Session session(runtime, std::move(options));
    if (session.start() != static_cast<std::size_t>(a.devices)) {
        for (const DeviceReport& d : runtime.report().devices) {
            if (!d.fault.empty()) {
                std::fprintf(stderr, "hapto soak: %s: %s\n", d.name.c_str(), d.fault.c_str());
            }
        }
        std::fprintf(stderr, "hapto soak: not every device could be opened\n");
        return 1;
    }

    WorldChurn churn(world, scene);
    SoakLog log(a, runtime, std::move(injectors));
    std::printf("%8s %-8s %10s %9s %11s %7s %6s %7s %9s\n", "t (s)", "device", "ticks", "rate Hz",
                "drift ppm", "missed", "faults", "down s", "rss MiB");
    std::optional<double> settleFromS;
    session.run([&](double tS) { return soakStep(tS, a, runtime, churn, log, settleFromS); });
    const double endS = session.timeS();
    if (endS - log.previousEndS() > 0.5 * a.windowS || log.windows().empty()) {
        log.closeWindow(endS);
    }
    const RunReport& r = session.stop();
    world.settle();
    // A stop request ends the session at once: no settling, and no verdict.
    const bool interrupted = control.stopRequested && control.stopRequested();
    return concludeSoak({a, spec, scene, world, churn, log, r, interrupted});
}

} // namespace hapto::experiments
