// Several simulated devices on one servo thread (RuntimeOptions::devicesPerThread = K > 1).
//
// Design note. One servo thread per device stays the design and the default: a device's
// thread waits only on that device. But a thread's sleep and wake-up cost the kernel several
// microseconds of CPU per tick, more than the tick itself (docs/results/many-devices.md), so
// 128 simulated hands at 1 kHz spend most of their CPU going to sleep and waking up. A
// simulated device never blocks in read() or write(), so for simulated devices only the
// runtime can put K of them on one thread: the thread sleeps once to the earliest deadline of
// its running members and then ticks every member due, earliest deadline first, each with the
// same ServoStep a lone device runs. So every member keeps its own deadline, cursor,
// renderer, effects, safety filter, load record (its wake-up is when its own tick starts, so
// waiting behind the group's earlier ticks shows as its lateness, and its load is its own
// work) and faults:
//   - a member whose tick faults (read, write, NaN) commands zero and leaves the group's loop;
//     the others run on; supervision closes and reopens it like any device and it rejoins the
//     group's loop at its restart (restartServo), with a deadline one period on;
//   - a group stalled (in one member's device, or by the host) stops every member's
//     heartbeat: the watchdog faults each, and each member commands zero at the thread's next
//     turn (the step's own stall check, or the stop flag below);
//   - stop() and emergencyStop() stop the group: each running member commands zero as the
//     thread leaves.
// In step mode stepAll() runs each group the same way on the caller's thread: the clock is the
// step's time for the group's first tick and moves on with each member's device I/O, as the
// group's one thread would see it.

#include "Channel.h"

#include <algorithm>
#include <stdexcept>
#include <unistd.h>

namespace hapto {

void Runtime::makeGroups() {
    const std::size_t k = mOptions.devicesPerThread;
    if (k == 0) {
        throw std::invalid_argument("runtime: devices per thread must be at least 1");
    }
    if (k == 1) {
        return;
    }
    for (const auto& chp : mChannels) {
        const DeviceConfig& c = chp->record.rd.config;
        if (c.kind != DeviceKind::Sim && c.kind != DeviceKind::Scripted) {
            throw std::invalid_argument(
                "runtime: " + std::to_string(k) +
                " devices per thread takes simulated devices only, and device '" + c.name +
                "' is " + std::string(name(c.kind)) +
                ": a hardware device gets its own servo thread, so that it waits on no other");
        }
    }
    const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
    for (std::size_t first = 0; first < mChannels.size(); first += k) {
        auto g = std::make_unique<Group>();
        const int index = static_cast<int>(mGroups.size());
        for (std::size_t i = first; i < std::min(first + k, mChannels.size()); ++i) {
            mChannels[i]->record.group = index;
            g->members.push_back(mChannels[i].get());
        }
        g->due.resize(g->members.size());
        g->cpu = mOptions.realtime ? static_cast<int>(mGroups.size() % cores) : -1;
        mGroups.push_back(std::move(g));
    }
}

void Runtime::restartServo(Channel& ch) {
    if (ch.record.group < 0) {
        startThread(ch);
    } else {
        startServo(ch, now()); // running again: the group's thread picks it up at its next turn
    }
}

void Runtime::tickDue(Group& g) noexcept {
    const std::uint64_t t = now();
    std::size_t due = 0;
    for (Channel* ch : g.members) {
        if (!ch->metrics.running.load(std::memory_order_acquire)) {
            continue; // faulted (supervision has it) or never opened
        }
        if (ch->servo.stop.load(std::memory_order_acquire)) {
            leaveServo(*ch); // stopped, or the watchdog fired while the group was away
            continue;
        }
        if (ch->servo.deadlineNs <= t) {
            // Insertion sort by deadline (ties: device order); K is small and this allocates
            // nothing.
            std::size_t at = due++;
            while (at > 0 && g.due[at - 1]->servo.deadlineNs > ch->servo.deadlineNs) {
                g.due[at] = g.due[at - 1];
                --at;
            }
            g.due[at] = ch;
        }
    }
    for (std::size_t i = 0; i < due; ++i) {
        Channel& ch = *g.due[i];
        if (ch.servo.stop.load(std::memory_order_acquire) || !ch.servo.run(now())) {
            leaveServo(ch);
        }
    }
}

void Runtime::groupMain(Group& g) {
    // Set-up: may allocate (the real-time grant's note), nothing below the loop entry does.
    rt::RealtimeGrant grant;
    rt::nameCurrentThread("hapto-group");
    if (mOptions.realtime) {
        grant = rt::makeCurrentThreadRealtime(mOptions.fifoPriority, g.cpu);
    } else {
        rt::tightenTimerSlack();
        grant.note = "real-time scheduling not requested";
    }
    const std::uint64_t t0 = rt::nowNs();
    for (Channel* ch : g.members) {
        ch->record.grant = grant;
        ch->metrics.threadId.store(static_cast<int>(gettid()), std::memory_order_relaxed);
        ch->metrics.realtime.store(grant.fifo, std::memory_order_relaxed);
        if (ch->metrics.running.load(std::memory_order_acquire)) {
            ch->servo.deadlineNs = t0 + ch->servo.periodNs;
        }
    }
    // With no member running (all faulted, waiting to be reopened), look again this often.
    const std::uint64_t idleNs = std::max<std::uint64_t>(g.members.front()->servo.periodNs, 1);

    rt::setInServoLoop(true);
    while (!g.stop.load(std::memory_order_acquire)) {
        std::uint64_t next = UINT64_MAX;
        for (Channel* ch : g.members) {
            if (ch->metrics.running.load(std::memory_order_acquire)) {
                next = std::min(next, ch->servo.deadlineNs);
            }
        }
        const std::uint64_t t = rt::nowNs();
        if (next == UINT64_MAX) {
            next = t + idleNs;
        }
        if (next > t) {
            rt::sleepUntilNs(next, mOptions.spinNs); // one sleep for every member then due
        }
        tickDue(g);
    }
    for (Channel* ch : g.members) {
        if (ch->metrics.running.load(std::memory_order_acquire)) {
            leaveServo(*ch);
        }
    }
    rt::setInServoLoop(false);
}

void Runtime::stepGroups(std::uint64_t nowNs) {
    for (auto& g : mGroups) {
        mClock->set(nowNs);
        rt::setInServoLoop(true);
        tickDue(*g);
        rt::setInServoLoop(false);
    }
    mClock->set(nowNs); // the other threads did not wait for this group
}

void Runtime::stopGroups() {
    for (auto& g : mGroups) {
        g->stop.store(true, std::memory_order_release);
    }
    for (auto& g : mGroups) {
        if (g->thread.joinable()) {
            g->thread.join(); // each running member commanded zero as it left
        }
    }
}

} // namespace hapto
