#pragma once
/// One device's block inside the Runtime (private to runtime/src): the servo thread's hot
/// state, what it shares with other threads, and the cold record supervision and reports use.
///
/// Design note. A Channel is laid out in four parts, by who touches them how often:
///   ServoStep       hot: everything one tick reads or writes and nothing else (the device
///                   pointer, the frames, the deadline, the sample, the haptic tick with its
///                   effects and hook, pointers to the parts below). Only the servo thread (or
///                   the stepping thread) touches it while the servo runs (its size: ServoStep.h).
///   DeviceMetrics   written every tick by the servo, read by any thread (its own lines).
///   three Mailboxes contacts out, external force in, every tick; effects in, when the control
///                   thread changes them, with a count the servo checks every tick (their own
///                   lines).
///   ChannelRecord   cold: the configuration and its strings, the threads, recovery flags,
///                   the fault record and event list under a mutex. Never touched by a tick.
/// Strings, vectors and mutexes live only in the record, so a tick's cache lines hold tick data.

#include "hapto/runtime/HapticTick.h"
#include "hapto/runtime/Realtime.h"
#include "hapto/runtime/Runtime.h"
#include "hapto/runtime/ServoStep.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

namespace hapto {

// What crosses threads through the mailboxes below is plain structs of vectors.
static_assert(std::is_trivially_copyable_v<ContactReport> && std::is_trivially_copyable_v<Vec3>);

/// The cold record of a channel.
struct ChannelRecord {
    RuntimeDevice rd;  ///< The device (owned), its configuration, its recorder.
    EffectSet effects; ///< The effects as the control thread last set them.
    int cpu = -1;      ///< The core its servo thread is pinned to, or -1.
    int group = -1;    ///< The servo group whose thread runs it (GroupedServo.cpp), or -1.
    std::thread thread;
    bool opened = false; ///< open() succeeded at start(); control thread only.
    std::string openError;
    rt::RealtimeGrant grant;

    // Fault recovery. Supervision hands a faulted device to recovery (recovering), which
    // closes it (down), reopens it and starts its servo again; with reopening off it stays
    // closed (gaveUp). `closed` makes sure one thread, and one only, closes it.
    std::atomic<bool> recovering{false}, down{false}, gaveUp{false}, closed{false};
    std::thread worker;             ///< The recovery worker (threaded mode).
    std::uint64_t nextReopenNs = 0; ///< Step mode: when to try to open again.

    mutable std::mutex mutex;      // guards the fields below: recovery writes, report() reads
    std::uint64_t downSinceNs = 0; // when the fault happened
    std::uint64_t faults = 0, reopens = 0, downNs = 0;
    std::string lastFault;       // what the last fault was, for the report
    std::string lastReopenError; // so a device that stays away is logged once, not per try
    std::vector<std::string> events;
    std::uint64_t eventsDropped = 0;
};

struct alignas(64) Runtime::Channel {
    ServoStep servo;                 ///< Hot.
    DeviceMetrics metrics;           ///< Servo -> any thread.
    Mailbox<ContactReport> contacts; ///< Servo -> control, every tick.
    Mailbox<Vec3> externalForce;     ///< Control -> servo, world frame (N).
    Mailbox<EffectSet> effects;      ///< Control -> servo, a new effect set when changed.
    std::atomic<std::uint64_t> effectsPublished{0}; ///< Sets published to `effects` so far.
    ChannelRecord record;                           ///< Cold.

    Channel(RuntimeDevice d, const RuntimeOptions& o);
};

/// Several simulated devices on one servo thread (RuntimeOptions::devicesPerThread). The
/// members' channels stay where they are; the group holds pointers to them, and `due` is the
/// tick's scratch list, sized at construction so a tick never allocates.
struct Runtime::Group {
    std::vector<Channel*> members; ///< In device order; fixed from construction.
    std::vector<Channel*> due;     ///< [servo] The members due at this wake-up, by deadline.
    int cpu = -1;                  ///< The core its thread is pinned to, or -1.
    std::thread thread;
    std::atomic<bool> stop{false}; ///< The thread leaves its loop (each member at zero force).
};

} // namespace hapto
