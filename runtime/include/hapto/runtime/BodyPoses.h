#pragma once
/// The dynamic bodies as the threads share them: each body's latest pose, published by the
/// dynamics thread and read by servo threads, the control thread and the view without locks,
/// and the impulses the hands hand back to each body, accumulated exactly.
///
/// Design note. A pose is a seqlock record: the one writer (the dynamics step) makes the
/// sequence odd, stores the fields, makes it even again; a reader copies the fields between two
/// equal even sequence reads and retries otherwise (a retry happens only when a publication
/// raced it; publications come once per dynamics step). The fields are relaxed atomics, so the
/// protocol is data-race free as C++ defines it and costs plain loads and stores on x86-64; two
/// fences order them against the sequence. ThreadSanitizer does not model fences (GCC's -Wtsan),
/// so under it the fields are stored with release and loaded with acquire instead, which orders
/// at least as much and lets it check the protocol. Impulses are summed in fixed point (int64,
/// kImpulseQuantumNs per unit) by atomic fetch_add and taken by exchange with zero: every servo
/// tick's contribution lands in exactly one dynamics step whatever the two rates, and integer sums
/// do not depend on the order in which threads add (the step mode's runs are byte-identical). The
/// hands' torsional friction budgets (BodyCoupling.h) are summed the same way, as the six
/// components of a symmetric tensor sum budget n n^T, which does not depend on a normal's sign: two
/// hands pressing from opposite sides add their budgets about their common axis. Nothing here
/// allocates after construction, locks or throws.

#include "hapto/core/Geometry.h"

#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>

// Under ThreadSanitizer the seqlock's fields carry the ordering instead of two fences (see
// the design note above).
#if defined(__SANITIZE_THREAD__)
#define HAPTO_SEQLOCK_WITHOUT_FENCES 1
#else
#define HAPTO_SEQLOCK_WITHOUT_FENCES 0
#endif

namespace hapto {

class Dynamics;

/// One body's state as published (world frame).
struct BodyPose {
    Vec3 center{0.0};          ///< The scene object's centre (SceneObject::center) (m).
    Quat rotation{1, 0, 0, 0}; ///< The scene object's rotation (unit).
    Vec3 centerOfMass{0.0};    ///< Centre of mass (m).
    Vec3 velocity{0.0};        ///< Of the centre of mass (m/s).
    Vec3 angularVelocity{0.0}; ///< (rad/s).
    std::uint64_t timeNs = 0;  ///< Session time of the state (ns, the runtime's clock).
    std::uint64_t step = 0;    ///< The dynamics step that produced it (0: the initial state).
    bool sleeping = false;     ///< The body is asleep.
};

/// The shared records of N bodies. Threading as marked per member.
class BodyPoseTable {
public:
    /// One impulse unit (N s): 1e-12, so a 1 kHz servo's 10 N for an hour sums far below
    /// int64's range and a 1 mN force over one 0.1 ms tick is still 10^5 units.
    static constexpr double kImpulseQuantumNs = 1e-12;

    /// N bodies, every pose at rest at the origin until published. [control]
    explicit BodyPoseTable(std::size_t bodies)
        : mCount(bodies), mRecords(std::make_unique<Record[]>(bodies)) {}

    /// Number of bodies. [any thread]
    std::size_t size() const noexcept { return mCount; }

    /// Publishes body i's pose. One writer per table. [dynamics]
    void publish(std::size_t i, const BodyPose& pose) noexcept {
        Record& r = mRecords[i];
        const std::uint64_t s = r.sequence.load(std::memory_order_relaxed);
        r.sequence.store(s + 1, std::memory_order_relaxed);
#if !HAPTO_SEQLOCK_WITHOUT_FENCES
        std::atomic_thread_fence(std::memory_order_release);
#endif
        const std::array<double, kFields> f = pack(pose);
        for (std::size_t k = 0; k < kFields; ++k) {
            r.fields[k].store(f[k], kFieldStore);
        }
        r.timeNs.store(pose.timeNs, kFieldStore);
        r.step.store(pose.step, kFieldStore);
        r.sleeping.store(pose.sleeping, kFieldStore);
        r.sequence.store(s + 2, std::memory_order_release);
    }

    /// Body i's latest pose: a consistent copy of one publication. Lock-free; retries only
    /// while a publication races it. [any thread]
    BodyPose read(std::size_t i) const noexcept {
        const Record& r = mRecords[i];
        for (;;) {
            const std::uint64_t s1 = r.sequence.load(std::memory_order_acquire);
            if ((s1 & 1u) != 0) {
                continue;
            }
            std::array<double, kFields> f{};
            for (std::size_t k = 0; k < kFields; ++k) {
                f[k] = r.fields[k].load(kFieldLoad);
            }
            BodyPose pose = unpack(f);
            pose.timeNs = r.timeNs.load(kFieldLoad);
            pose.step = r.step.load(kFieldLoad);
            pose.sleeping = r.sleeping.load(kFieldLoad);
#if !HAPTO_SEQLOCK_WITHOUT_FENCES
            std::atomic_thread_fence(std::memory_order_acquire);
#endif
            if (r.sequence.load(std::memory_order_relaxed) == s1) {
                return pose;
            }
        }
    }

    /// Adds an impulse to body i: linear (N s, world) and angular about its centre of mass
    /// (N m s, world), rounded to kImpulseQuantumNs. Lock-free, any number of adders. Returns
    /// false (and adds nothing) for a non-finite or out-of-range impulse. [servo]
    bool addImpulse(std::size_t i, const Vec3& linearNs, const Vec3& angularNms) noexcept {
        std::array<std::int64_t, 6> q{};
        for (int k = 0; k < 3; ++k) {
            if (!quantise(linearNs[k], q[k]) || !quantise(angularNms[k], q[3 + k])) {
                return false;
            }
        }
        Record& r = mRecords[i];
        for (int k = 0; k < 6; ++k) {
            r.impulse[k].fetch_add(q[k], std::memory_order_relaxed);
        }
        return true;
    }

    /// Takes body i's accumulated impulse (what addImpulse summed since the last take) and
    /// resets it to zero. [dynamics]
    void takeImpulse(std::size_t i, Vec3& linearNs, Vec3& angularNms) noexcept {
        Record& r = mRecords[i];
        for (int k = 0; k < 3; ++k) {
            linearNs[k] = static_cast<double>(r.impulse[k].exchange(0, std::memory_order_relaxed)) *
                          kImpulseQuantumNs;
            angularNms[k] =
                static_cast<double>(r.impulse[3 + k].exchange(0, std::memory_order_relaxed)) *
                kImpulseQuantumNs;
        }
    }

    /// Adds a torsional-friction budget to body i: `budgetNms` (N m s, >= 0) about the unit
    /// axis `axis` (world; either sign), summed as budgetNms axis axis^T, rounded to
    /// kImpulseQuantumNs. Lock-free, any number of adders. Returns false (and adds nothing)
    /// for a negative, non-finite or out-of-range budget or axis. [servo]
    bool addTorsion(std::size_t i, const Vec3& axis, double budgetNms) noexcept {
        if (!(budgetNms >= 0.0)) {
            return false;
        }
        const std::array<double, 6> t{axis.x * axis.x, axis.y * axis.y, axis.z * axis.z,
                                      axis.x * axis.y, axis.x * axis.z, axis.y * axis.z};
        std::array<std::int64_t, 6> q{};
        for (int k = 0; k < 6; ++k) {
            if (!quantise(budgetNms * t[k], q[k])) {
                return false;
            }
        }
        Record& r = mRecords[i];
        for (int k = 0; k < 6; ++k) {
            r.torsion[k].fetch_add(q[k], std::memory_order_relaxed);
        }
        return true;
    }

    /// Takes body i's accumulated torsional budget (what addTorsion summed since the last
    /// take: a symmetric tensor, N m s) and resets it to zero. [dynamics]
    Mat3 takeTorsion(std::size_t i) noexcept {
        Record& r = mRecords[i];
        std::array<double, 6> t{};
        for (int k = 0; k < 6; ++k) {
            t[k] = static_cast<double>(r.torsion[k].exchange(0, std::memory_order_relaxed)) *
                   kImpulseQuantumNs;
        }
        Mat3 m(0.0);
        m[0][0] = t[0];
        m[1][1] = t[1];
        m[2][2] = t[2];
        m[0][1] = m[1][0] = t[3];
        m[0][2] = m[2][0] = t[4];
        m[1][2] = m[2][1] = t[5];
        return m;
    }

private:
    static constexpr std::size_t kFields = 16;
    /// How a record's fields are stored and loaded: relaxed between the fences, or release and
    /// acquire where the fences are left out (HAPTO_SEQLOCK_WITHOUT_FENCES).
    static constexpr std::memory_order kFieldStore =
        HAPTO_SEQLOCK_WITHOUT_FENCES ? std::memory_order_release : std::memory_order_relaxed;
    static constexpr std::memory_order kFieldLoad =
        HAPTO_SEQLOCK_WITHOUT_FENCES ? std::memory_order_acquire : std::memory_order_relaxed;
    struct alignas(64) Record {
        std::atomic<std::uint64_t> sequence{0};
        std::array<std::atomic<double>, kFields> fields{};
        std::atomic<std::uint64_t> timeNs{0};
        std::atomic<std::uint64_t> step{0};
        std::atomic<bool> sleeping{false};
        std::array<std::atomic<std::int64_t>, 6> impulse{};
        /// The torsional budget's xx, yy, zz, xy, xz, yz (quanta).
        std::array<std::atomic<std::int64_t>, 6> torsion{};
    };

    static std::array<double, kFields> pack(const BodyPose& p) noexcept {
        return {p.center.x,       p.center.y,          p.center.z,          p.rotation.w,
                p.rotation.x,     p.rotation.y,        p.rotation.z,        p.centerOfMass.x,
                p.centerOfMass.y, p.centerOfMass.z,    p.velocity.x,        p.velocity.y,
                p.velocity.z,     p.angularVelocity.x, p.angularVelocity.y, p.angularVelocity.z};
    }
    static BodyPose unpack(const std::array<double, kFields>& f) noexcept {
        BodyPose p;
        p.center = Vec3(f[0], f[1], f[2]);
        p.rotation = Quat(f[3], f[4], f[5], f[6]);
        p.centerOfMass = Vec3(f[7], f[8], f[9]);
        p.velocity = Vec3(f[10], f[11], f[12]);
        p.angularVelocity = Vec3(f[13], f[14], f[15]);
        return p;
    }
    static bool quantise(double v, std::int64_t& out) noexcept {
        const double q = v / kImpulseQuantumNs;
        if (!std::isfinite(q) || std::fabs(q) > 9.0e18) {
            return false;
        }
        out = std::llround(q);
        return true;
    }

    std::size_t mCount;
    std::unique_ptr<Record[]> mRecords;
};

/// Body i of `dynamics` as the dynamics thread publishes it: its object's pose, centre of
/// mass, velocities, sleep flag and step count, stamped `timeNs` (the runtime's clock). The one
/// conversion from a dynamics state to a table record (the dynamics thread and test rigs that
/// step a Dynamics themselves use it). [dynamics]
BodyPose bodyPoseOf(const Dynamics& dynamics, std::size_t i, std::uint64_t timeNs) noexcept;

} // namespace hapto
