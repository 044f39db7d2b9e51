// Reports: the run's summary from each device's metrics and record, as values, as JSON (the
// `hapto run --report` format) and as one live line per device. Nothing here runs on a servo
// thread; report() takes each device's record lock briefly, never a servo's. The dynamics
// thread is reported like a device (its load, misses and verdict by the same rule, loadStable)
// with each body's measured figures.

#include "Channel.h"
#include "DynamicsChannel.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>

namespace hapto {

const char* faultName(FaultKind kind) noexcept {
    switch (kind) {
    case FaultKind::None:
        return "none";
    case FaultKind::OpenFailed:
        return "open-failed";
    case FaultKind::ReadFailed:
        return "read-failed";
    case FaultKind::WriteFailed:
        return "write-failed";
    case FaultKind::NonFinite:
        return "non-finite";
    case FaultKind::Watchdog:
        return "watchdog";
    }
    return "unknown";
}

namespace {

/// A histogram of times (ns) as fractions of `periodNs`.
HistogramSummary asFractionOf(const HistogramSummary& t, double periodNs) {
    return {t.count,          t.mean / periodNs, t.p50 / periodNs,
            t.p99 / periodNs, t.p999 / periodNs, t.max / periodNs};
}

} // namespace

bool loadStable(std::uint64_t steps, const HistogramSummary& loadFraction,
                std::uint64_t missedDeadlines) {
    return steps > 0 && loadFraction.p999 < 1.0 &&
           static_cast<double>(missedDeadlines) <= 0.001 * static_cast<double>(steps);
}

std::optional<DynamicsReport> Runtime::dynamicsReport() const {
    if (!mDynamics) {
        return std::nullopt;
    }
    const DynamicsChannel& dc = *mDynamics;
    const DynamicsMetrics& m = dc.metrics;
    DynamicsReport d;
    d.rateHz = dc.rateHz;
    d.steps = m.steps.load();
    d.stepNs = m.stepNs.summary();
    d.loadFraction = asFractionOf(d.stepNs, static_cast<double>(dc.periodNs));
    d.latenessNs = m.latenessNs.summary();
    d.lateWakeups = m.lateWakeups.load();
    d.missedDeadlines = m.missedDeadlines.load();
    d.stoppedBodies = m.stoppedBodies.load();
    d.realtime = m.realtime.load();
    if (m.fault.load(std::memory_order_acquire) != FaultKind::None) {
        const std::uint64_t at = m.faultNs.load();
        char text[160];
        std::snprintf(text, sizeof text,
                      "%s: no step for %.1f ms (bound %.1f ms); bodies frozen "
                      "at step %llu",
                      faultName(m.fault.load()), static_cast<double>(at - m.stateNs.load()) * 1e-6,
                      static_cast<double>(dc.stallBoundNs) * 1e-6,
                      static_cast<unsigned long long>(m.frozenAtStep.load()));
        d.fault = text;
        d.faultS = static_cast<double>(at - mStartNs) * 1e-9;
    }
    d.stable = loadStable(d.steps, d.loadFraction, d.missedDeadlines) && d.stoppedBodies == 0 &&
               d.fault.empty();
    for (std::size_t i = 0; i < dc.ids.size(); ++i) {
        const DynamicsBodyRecord& b = dc.records[i];
        d.bodies.push_back(BodyReport{dc.ids[i], b.deepestPenetrationM.load(),
                                      b.largestEnergyGainJ.load(), b.stopped.load()});
    }
    return d;
}

RunReport Runtime::report() const {
    RunReport r;
    r.cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
    r.dynamics = dynamicsReport();
    r.stable = !mChannels.empty() || r.dynamics.has_value();
    if (r.dynamics) {
        r.stable = r.dynamics->stable;
    }
    for (const auto& chp : mChannels) {
        const Channel& ch = *chp;
        const ChannelRecord& c = ch.record;
        const DeviceMetrics& m = ch.metrics;
        DeviceReport d;
        d.name = c.rd.config.name;
        d.kind = std::string(name(c.rd.config.kind));
        d.rateHz = c.rd.config.rateHz;
        d.ticks = m.ticks.load();
        HistogramSummary t = m.tickNs.summary();
        d.loadFraction = asFractionOf(t, static_cast<double>(ch.servo.periodNs));
        d.latenessNs = m.latenessNs.summary();
        d.ioNs = m.ioNs.summary();
        d.lateWakeups = m.lateWakeups.load();
        d.missedDeadlines = m.missedDeadlines.load();
        d.zeroedForMisses = m.zeroedForMisses.load();
        const double ticks = static_cast<double>(std::max<std::uint64_t>(1, d.ticks));
        d.locateStepsMean = static_cast<double>(m.locateStepsSum.load()) / ticks;
        d.candidatesMean = static_cast<double>(m.candidatesSum.load()) / ticks;
        d.outsideTicks = m.outsideTicks.load();
        d.contactTicks = m.contactTicks.load();
        d.snapshotsSeen = m.snapshotsSeen.load();
        d.safety = ch.servo.haptic.safety().counters();
        d.hookNonFinite = m.hookNonFinite.load();
        d.realtime = m.realtime.load(std::memory_order_relaxed);
        std::lock_guard lock(c.mutex);
        const FaultKind f = m.fault.load();
        const bool down = c.down.load(std::memory_order_acquire);
        if (f == FaultKind::OpenFailed) {
            d.fault = std::string("open-failed: ") + c.openError;
        } else if (down) {
            d.fault = c.lastFault;
        } else if (f != FaultKind::None) { // faulted, not yet taken by the supervisor
            d.fault = faultText(ch);
        }
        d.faults = c.faults + (f != FaultKind::None && f != FaultKind::OpenFailed && !down);
        d.reopens = c.reopens;
        const std::uint64_t nowNs = now();
        const std::uint64_t downNow = down && nowNs > c.downSinceNs ? nowNs - c.downSinceNs : 0;
        d.downS = static_cast<double>(c.downNs + downNow) * 1e-9;
        d.events = c.events;
        if (c.eventsDropped > 0) {
            d.events.push_back("... and " + std::to_string(c.eventsDropped) + " more events");
        }
        d.stable = d.fault.empty() && d.faults == 0 &&
                   loadStable(d.ticks, d.loadFraction, d.missedDeadlines);
        r.loadSum += d.loadFraction.mean;
        r.stable = r.stable && d.stable;
        r.devices.push_back(std::move(d));
    }
    r.loadPerCore = r.loadSum / r.cores;
    const std::uint64_t stoppedAt = mStopNs.load();
    const std::uint64_t end = stoppedAt ? stoppedAt : now();
    r.durationS = mStartNs ? static_cast<double>(end - mStartNs) * 1e-9 : 0.0;
    r.realtimeNote = mRealtimeNote;
    r.wakeLatencyUs = mHeldWakeLatencyUs;
    r.warmUpNs = mGroups.empty() ? mWarmUpNs : 0; // groups never warm up
    r.warmUpAutomatic = !mOptions.warmUpNs.has_value();
    return r;
}

std::string Runtime::liveLine(std::size_t i) const {
    const Channel& ch = *mChannels.at(i);
    const DeviceMetrics& m = ch.metrics;
    const HistogramSummary t = m.tickNs.summary();
    const double period = static_cast<double>(ch.servo.periodNs);
    const Vec3 f(m.forceN[0].load(), m.forceN[1].load(), m.forceN[2].load());
    char line[256];
    std::snprintf(line, sizeof line,
                  "%-10s %9llu ticks  load p50 %5.1f%%  p99.9 %5.1f%%  max %6.1f%%  missed %llu  "
                  "|F| %5.2f N%s",
                  ch.record.rd.config.name.c_str(), static_cast<unsigned long long>(m.ticks.load()),
                  100.0 * t.p50 / period, 100.0 * t.p999 / period, 100.0 * t.max / period,
                  static_cast<unsigned long long>(m.missedDeadlines.load()), glm::length(f),
                  m.fault.load() != FaultKind::None ? "  FAULTED" : "");
    return line;
}

std::string lateWakeupNote(const DeviceReport& d) {
    // The verdict's rule (Runtime::report): misses <= 0.1 % of the ticks. Ticks that took
    // their whole period are at most the 0.1 % above the p99.9; 0.9 keeps the histogram's 3 %
    // bucket precision well clear of that bound.
    const std::uint64_t longTicks = d.ticks / 1000;
    if (!d.fault.empty() || d.faults > 0 || d.stable || d.ticks == 0 ||
        !(d.loadFraction.p999 < 0.9) || d.missedDeadlines <= longTicks) {
        return {};
    }
    char text[512];
    std::snprintf(text, sizeof text,
                  "%llu missed deadlines (%.2f %% of its ticks; a stable device misses at most "
                  "0.1 %%), at least %llu of them ticks shorter than their period that started "
                  "late (the latest wake-up %.2f ms after its deadline): the operating system or "
                  "the virtual machine did not run the servo thread on time; the tick's own work "
                  "stayed small (p99.9 load %.2f %%)",
                  static_cast<unsigned long long>(d.missedDeadlines),
                  100.0 * static_cast<double>(d.missedDeadlines) / static_cast<double>(d.ticks),
                  static_cast<unsigned long long>(d.missedDeadlines - longTicks),
                  d.latenessNs.max * 1e-6, 100.0 * d.loadFraction.p999);
    return text;
}

namespace {

nlohmann::json summaryJson(const HistogramSummary& s) {
    return nlohmann::json{
        {"mean", s.mean}, {"p50", s.p50}, {"p99", s.p99}, {"p999", s.p999}, {"max", s.max}};
}

/// The dynamics thread's part of the report: its row and one per body.
nlohmann::json dynamicsJson(const DynamicsReport& d) {
    using nlohmann::json;
    json bodies = json::array();
    for (const BodyReport& b : d.bodies) {
        bodies.push_back(json{{"id", b.id},
                              {"deepest_penetration_m", b.deepestPenetrationM},
                              {"largest_energy_gain_j", b.largestEnergyGainJ},
                              {"stopped_non_finite", b.stopped}});
    }
    return json{{"rate_hz", d.rateHz},
                {"steps", d.steps},
                {"step_ns", summaryJson(d.stepNs)},
                {"load", summaryJson(d.loadFraction)},
                {"lateness_ns", summaryJson(d.latenessNs)},
                {"late_wakeups", d.lateWakeups},
                {"missed_deadlines", d.missedDeadlines},
                {"stopped_bodies", d.stoppedBodies},
                {"fault", d.fault},
                {"fault_s", d.faultS},
                {"realtime", d.realtime},
                {"stable", d.stable},
                {"bodies", bodies}};
}

} // namespace

std::string reportToJson(const RunReport& r) {
    using nlohmann::json;
    const auto load = [](const HistogramSummary& s) { return summaryJson(s); };
    json devices = json::array();
    for (const DeviceReport& d : r.devices) {
        devices.push_back(json{
            {"name", d.name},
            {"kind", d.kind},
            {"rate_hz", d.rateHz},
            {"ticks", d.ticks},
            {"load", load(d.loadFraction)},
            {"late_wakeups", d.lateWakeups},
            {"missed_deadlines", d.missedDeadlines},
            {"zeroed_for_misses", d.zeroedForMisses},
            {"lateness_ns", load(d.latenessNs)},
            {"io",
             {{"mean_ns", d.ioNs.mean},
              {"p99_ns", d.ioNs.p99},
              {"max_ns", d.ioNs.max},
              {"fraction_of_tick", d.loadFraction.mean > 0
                                       ? d.ioNs.mean / (d.loadFraction.mean * 1e9 / d.rateHz)
                                       : 0.0}}},
            {"locate_steps_mean", d.locateStepsMean},
            {"candidates_mean", d.candidatesMean},
            {"outside_ticks", d.outsideTicks},
            {"contact_ticks", d.contactTicks},
            {"snapshots_seen", d.snapshotsSeen},
            {"safety",
             {{"clamped", d.safety.clamped},
              {"rate_limited", d.safety.rateLimited},
              {"non_finite", d.safety.nonFinite},
              {"overflowed", d.safety.overflowed}}},
            {"hook_non_finite", d.hookNonFinite},
            {"faults", d.faults},
            {"fault", d.fault},
            {"reopens", d.reopens},
            {"down_s", d.downS},
            {"events", d.events},
            {"realtime", d.realtime},
            {"stable", d.stable},
        });
        if (std::string note = lateWakeupNote(d); !note.empty()) {
            devices.back()["note"] = std::move(note); // what hapto run prints under the row
        }
    }
    json total{{"load_sum", r.loadSum},
               {"load_per_core", r.loadPerCore},
               {"cores", r.cores},
               {"stable", r.stable},
               {"duration_s", r.durationS}};
    total["warm_up_us"] = static_cast<double>(r.warmUpNs) / 1000.0;
    total["warm_up_automatic"] = r.warmUpAutomatic;
    if (r.wakeLatencyUs >= 0) {
        total["wake_latency_us"] = r.wakeLatencyUs;
    }
    json out{{"devices", devices}, {"total", total}};
    if (r.dynamics) {
        out["dynamics"] = dynamicsJson(*r.dynamics);
    }
    if (!r.realtimeNote.empty()) {
        out["realtime_note"] = r.realtimeNote;
    }
    return out.dump(2) + "\n";
}

} // namespace hapto
