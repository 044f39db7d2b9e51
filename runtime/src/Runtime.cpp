// The runtime's set-up and shutdown. Design note: each device owns one Channel (Channel.h), a
// cache-line-aligned block with its hot servo state apart from its cold record. Threads share
// only the read-only World snapshots. Everything is sized before a servo starts. The servo
// step lives in ServoStep.cpp and its loop in ServoLoop.cpp, supervision (the watchdog,
// closing, reopening) in Supervision.cpp, reports in RunReport.cpp; this file opens devices,
// starts the threads (or the step mode, which runs the same step and the same supervision pass
// on the caller's thread with the caller's clock), and stops them. When the world's scene has
// dynamic bodies, the runtime builds their Dynamics here from the world's first snapshot and
// owns it with its dynamics thread (DynamicsLoop.cpp); every servo gets its pose table.

#include "Channel.h"
#include "DynamicsChannel.h"

#include "hapto/runtime/Realtime.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hapto {

namespace {

SafetyConfig safetyFor(double maxForceN) {
    SafetyConfig c;
    if (maxForceN > 0) {
        c.maxForceN = maxForceN;
    }
    return c;
}

/// The device's configured effects, checked; a message names the device.
EffectSet effectsFor(const RuntimeDevice& device) {
    try {
        return EffectSet(device.rendering.effects);
    } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("runtime: device '" + device.config.name + "': " + e.what());
    }
}

} // namespace

Runtime::Channel::Channel(RuntimeDevice d, const RuntimeOptions& o)
    : servo(withDeviceSettings(o.renderer, d.rendering.renderer, d.config.transform.scale),
            safetyFor(d.config.maxForceN)) {
    record.effects = effectsFor(d);
    servo.haptic.setEffects(record.effects); // before any thread: no publish needed
    const std::uint64_t period = static_cast<std::uint64_t>(std::llround(1e9 / d.config.rateHz));
    servo.device = d.device.get();
    servo.recorder = d.recorder;
    servo.transform = d.config.transform;
    servo.toolTip = d.config.toolTipM;
    servo.setTiming(period, o.missLimit, o.lateWakeupFraction, o.stallTimeoutNs);
    record.rd = std::move(d);
}

Runtime::Runtime(World& world, std::vector<RuntimeDevice> devices, RuntimeOptions options)
    : mWorld(world), mOptions(options) {
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    for (std::size_t i = 0; i < devices.size(); ++i) {
        if (!devices[i].device) {
            throw std::invalid_argument("runtime: device " + std::to_string(i) + " is null");
        }
        if (!(devices[i].config.rateHz > 0) || !std::isfinite(devices[i].config.rateHz)) {
            throw std::invalid_argument("runtime: device '" + devices[i].config.name +
                                        "' has no servo rate");
        }
        auto ch = std::make_unique<Channel>(std::move(devices[i]), mOptions);
        ch->record.cpu = mOptions.realtime ? static_cast<int>(i % cores) : -1;
        mChannels.push_back(std::move(ch));
    }
    makeGroups();
    if (mWorld.current().scene->hasDynamicBodies()) {
        mDynamics = std::make_unique<DynamicsChannel>(mWorld.current(), mOptions);
    }
    // The warm-up spins on its core until the deadline: free on a core of its own; on a shared
    // one it costs CPU the other servo threads could use, for little (their ticks keep the
    // caches warm for each other; docs/results/many-devices.md).
    mWarmUpNs = mOptions.warmUpNs.value_or(
        mGroups.empty() && mChannels.size() <= cores ? kDefaultWarmUpNs : 0);
}

Runtime::~Runtime() {
    stop();
}

std::uint64_t Runtime::now() const noexcept {
    return mClock ? mClock->nowNs() : rt::nowNs();
}

void Runtime::requireStepped(const char* what) const {
    if (!mClock) {
        throw std::logic_error(std::string("Runtime::") + what +
                               ": only in step mode (after startStepped())");
    }
}

std::size_t Runtime::openAll() {
    mStarted = true;
    mStartNs = now();
    // Every device is opened before any servo starts (the PHANToM's HD scheduler must not run
    // while another device is being initialised; a Falcon homes with zero force).
    std::size_t opened = 0;
    for (auto& chp : mChannels) {
        Channel& ch = *chp;
        ChannelRecord& c = ch.record;
        const DeviceStatus st = c.rd.device->open();
        if (st != DeviceStatus::Ok) {
            c.openError = std::string(statusName(st)) + ": " + c.rd.device->errorMessage();
            ch.metrics.fault.store(FaultKind::OpenFailed);
            ch.metrics.faultStatus.store(static_cast<std::uint8_t>(st));
            c.closed.store(true);
            continue;
        }
        c.opened = true;
        c.closed.store(false);
        ch.servo.reader = mWorld.registerReader();
        ++opened;
    }
    mStopping.store(false);
    return opened;
}

std::size_t Runtime::start() {
    if (mOptions.wakeLatencyUs >= 0) {
        mWakeLatency = rt::WakeLatencyHold(mOptions.wakeLatencyUs);
        mHeldWakeLatencyUs = mWakeLatency.held() ? mWakeLatency.us() : -1;
        if (!mWakeLatency.held()) {
            mRealtimeNote += (mRealtimeNote.empty() ? "" : "; ") + mWakeLatency.note();
        }
    }
    const std::size_t started = openAll();
    if (mDynamics) {
        startDynamics(now()); // its poses are published before any servo reads them
    }
    for (auto& chp : mChannels) {
        if (chp->record.opened) {
            if (chp->record.group < 0) {
                startThread(*chp);
            } else {
                startServo(*chp, now()); // its group's thread runs it
            }
        }
    }
    for (auto& g : mGroups) {
        if (std::any_of(g->members.begin(), g->members.end(),
                        [](const Channel* ch) { return ch->record.opened; })) {
            g->thread = std::thread([this, &group = *g] { groupMain(group); });
        }
    }
    mSupervisor = std::thread([this] { superviseMain(); });
    return started;
}

std::size_t Runtime::startStepped(ManualClock& clock) {
    mClock = &clock;
    const std::size_t opened = openAll();
    if (mDynamics) {
        startDynamics(mStartNs); // its poses are published before any servo reads them
    }
    for (auto& chp : mChannels) {
        if (chp->record.opened) {
            startServo(*chp, mStartNs);
        }
    }
    return opened;
}

std::uint64_t Runtime::nextDeadlineNs(std::size_t i) const {
    return mChannels.at(i)->servo.deadlineNs;
}

void Runtime::maintain() {
    if (mDynamics) {
        // The bodies asleep now, read from the table (lock-free): the world puts those at rest
        // for its rest delay into the static index and takes woken ones out (World.h).
        std::vector<BodyRest> resting;
        for (std::size_t i = 0; i < mDynamics->ids.size(); ++i) {
            const BodyPose p = mDynamics->poses.read(i);
            if (p.sleeping && !mDynamics->records[i].stopped.load(std::memory_order_relaxed)) {
                resting.push_back(
                    {mDynamics->ids[i], false, p.center, p.rotation, p.centerOfMass, 0});
            }
        }
        mWorld.setRestingBodies(std::move(resting));
    }
    mWorld.maintain();
}

void Runtime::stop() {
    {
        std::lock_guard wake(mWakeMutex);
        mStopping.store(true, std::memory_order_release);
    }
    mWake.notify_all();
    for (auto& ch : mChannels) {
        ch->servo.stop.store(true, std::memory_order_release);
    }
    if (mSupervisor.joinable()) {
        mSupervisor.join();
    }
    for (auto& chp : mChannels) {
        if (chp->record.worker.joinable()) {
            chp->record.worker.join(); // returns at once, or when a reopen in progress returns
        }
    }
    stopGroups(); // no worker restarts a member now
    for (auto& chp : mChannels) {
        Channel& ch = *chp;
        ChannelRecord& c = ch.record;
        ch.servo.stop.store(true, std::memory_order_release); // a thread a worker just started
        if (c.thread.joinable()) {
            c.thread.join();
        }
        if (mClock && ch.metrics.running.load(std::memory_order_acquire)) {
            leaveServo(ch); // step mode: the servo commands zero here
        }
        c.recovering.store(false, std::memory_order_release);
        if (c.opened) {
            if (!c.closed.exchange(true)) {
                c.rd.device->close();
            }
            mWorld.unregisterReader(ch.servo.reader);
            ch.servo.reader = nullptr;
            c.opened = false;
            if (!c.grant.note.empty() && mRealtimeNote.find(c.grant.note) == std::string::npos) {
                mRealtimeNote += (mRealtimeNote.empty() ? "" : "; ") + c.grant.note;
            }
        }
    }
    stopDynamics();                       // after the servos: none hands it an impulse any more
    mWakeLatency = rt::WakeLatencyHold(); // every servo thread has stopped: idle CPUs may sleep
    std::uint64_t none = 0;
    if (mStartNs != 0) {
        mStopNs.compare_exchange_strong(none, now());
    }
}

void Runtime::emergencyStop(std::uint64_t waitNs) noexcept {
    mStopping.store(true, std::memory_order_release);
    for (auto& ch : mChannels) {
        ch->servo.stop.store(true, std::memory_order_release);
    }
    for (auto& g : mGroups) {
        g->stop.store(true, std::memory_order_release); // each member commands zero as it leaves
    }
    if (mDynamics) {
        mDynamics->stop.store(true, std::memory_order_release); // it drives no device
    }
    if (mClock) {
        for (auto& chp : mChannels) {
            if (chp->metrics.running.load(std::memory_order_acquire)) {
                leaveServo(*chp);
            }
        }
    }
    // Each servo thread commands zero as it leaves its loop (at its next check).
    const std::uint64_t until = rt::nowNs() + waitNs;
    const auto anyInLoop = [this] {
        return std::any_of(mChannels.begin(), mChannels.end(), [](auto& ch) {
            return ch->metrics.running.load(std::memory_order_acquire);
        });
    };
    while (anyInLoop() && rt::nowNs() < until) {
        rt::sleepUntilNs(rt::nowNs() + 1'000'000, 0);
    }
    for (auto& chp : mChannels) {
        Channel& ch = *chp;
        ChannelRecord& c = ch.record;
        if (!ch.metrics.running.load(std::memory_order_acquire) &&
            (mClock || !c.recovering.load(std::memory_order_acquire)) && !c.closed.exchange(true)) {
            c.rd.device->close(); // zero force, and the device's own I/O ends
        }
    }
}

bool Runtime::anyRunning() const {
    if (mStopping.load(std::memory_order_acquire)) {
        return false;
    }
    if (mDynamics && mDynamics->metrics.running.load(std::memory_order_acquire)) {
        return true;
    }
    return std::any_of(mChannels.begin(), mChannels.end(), [](auto& ch) {
        return ch->record.opened && !ch->record.gaveUp.load(std::memory_order_acquire);
    });
}

const DeviceMetrics& Runtime::metrics(std::size_t i) const {
    return mChannels.at(i)->metrics;
}
std::size_t Runtime::deviceCount() const {
    return mChannels.size();
}
Device& Runtime::device(std::size_t i) {
    return *mChannels.at(i)->record.rd.device;
}

bool Runtime::lastTick(std::size_t i, ContactReport& report) const {
    return mChannels.at(i)->contacts.read(report);
}

void Runtime::setExternalForce(std::size_t i, const Vec3& forceN) {
    mChannels.at(i)->externalForce.publish(forceN);
}

namespace {

/// Hands `effects` to the servo: publish, then count, so a servo that sees the count finds
/// that set (or a newer one) in the mailbox. [control]
void publishEffects(Mailbox<EffectSet>& mailbox, std::atomic<std::uint64_t>& published,
                    const EffectSet& effects) {
    mailbox.publish(effects);
    published.store(published.load(std::memory_order_relaxed) + 1, std::memory_order_release);
}

} // namespace

void Runtime::setEffects(std::size_t i, std::span<const ForceEffect> effects) {
    Channel& ch = *mChannels.at(i);
    try {
        ch.record.effects = EffectSet(effects);
    } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("Runtime::setEffects: device '" + ch.record.rd.config.name +
                                    "': " + e.what());
    }
    publishEffects(ch.effects, ch.effectsPublished, ch.record.effects);
}

void Runtime::setEffects(std::size_t i, std::initializer_list<ForceEffect> effects) {
    setEffects(i, std::span<const ForceEffect>(effects.begin(), effects.size()));
}

void Runtime::setEffectEnabled(std::size_t i, std::size_t k, bool enabled) {
    Channel& ch = *mChannels.at(i);
    if (!ch.record.effects.setEnabled(k, enabled)) {
        throw std::out_of_range("Runtime::setEffectEnabled: device '" + ch.record.rd.config.name +
                                "' has no effect " + std::to_string(k) + " (it has " +
                                std::to_string(ch.record.effects.size()) + ")");
    }
    publishEffects(ch.effects, ch.effectsPublished, ch.record.effects);
}

const EffectSet& Runtime::effects(std::size_t i) const {
    return mChannels.at(i)->record.effects;
}

void Runtime::setTickHook(std::size_t i, const TickHook& hook) {
    Channel& ch = *mChannels.at(i);
    if (mStarted) {
        throw std::logic_error("Runtime::setTickHook: register hooks before start() or "
                               "startStepped()");
    }
    ch.servo.haptic.setHook(hook);
}

} // namespace hapto
