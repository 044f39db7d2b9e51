// PhantomDevice against the stand-in HD library built from fakehd/FakeHD.cpp.
// Tests wait for conditions with generous bounded timeouts and never assert durations.

#include "TestSupport.h"

#include "hapto/devices/PhantomDevice.h"

#include <catch2/catch.hpp>

#include <dlfcn.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <stdexcept>
#include <string>
#include <thread>

using namespace hapto;
using hapto::test::eventually;

namespace {

const std::string kFakeLibrary = HAPTO_FAKEHD_LIBRARY;
constexpr int kDefault = 0; // "Default Device"
constexpr int kLeft = 1;    // "Left Touch"
constexpr int kRight = 2;   // "Right Touch"

/// The stand-in library's test hooks, resolved from the same loaded copy PhantomDevice uses.
/// Resets the stand-in at construction, so declare it before any device.
struct FakeHd {
    void (*reset)();
    void (*setMotion)(int, double, double, double, double, double, double);
    void (*setButtons)(int, int);
    void (*setStylus)(int, double, double, double, double, double, double, double);
    void (*lastForce)(int, double*);
    unsigned long long (*forceFrames)(int);
    double (*maxForceSeen)(int);
    void (*injectError)(int, unsigned, int);
    void (*stall)(int);
    void (*removeDevice)(int);
    int (*isInitialised)(int);
    int (*forceOutputEnabled)(int);
    int (*schedulerRunning)();
    int (*callbacksScheduled)();
    int (*maxDevicesPerTick)();
    int (*initWhileRunning)();
    unsigned long long (*step)(int);

    FakeHd() {
        mLib = dlopen(kFakeLibrary.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!mLib) {
            throw std::runtime_error(std::string("cannot load the stand-in HD library: ") +
                                     dlerror());
        }
        get("fakehd_reset", reset);
        get("fakehd_set_motion", setMotion);
        get("fakehd_set_buttons", setButtons);
        get("fakehd_set_stylus", setStylus);
        get("fakehd_last_force", lastForce);
        get("fakehd_force_frames", forceFrames);
        get("fakehd_max_force_seen", maxForceSeen);
        get("fakehd_inject_error", injectError);
        get("fakehd_stall", stall);
        get("fakehd_remove_device", removeDevice);
        get("fakehd_is_initialised", isInitialised);
        get("fakehd_force_output_enabled", forceOutputEnabled);
        get("fakehd_scheduler_running", schedulerRunning);
        get("fakehd_callbacks_scheduled", callbacksScheduled);
        get("fakehd_max_devices_per_tick", maxDevicesPerTick);
        get("fakehd_init_while_running", initWhileRunning);
        get("fakehd_step", step);
        reset();
    }
    ~FakeHd() {
        stall(0);
        dlclose(mLib); // PhantomDevice's own dlopen keeps it loaded
    }
    FakeHd(const FakeHd&) = delete;
    FakeHd& operator=(const FakeHd&) = delete;

    Vec3 force(int dev) const {
        double f[3];
        lastForce(dev, f);
        return Vec3(f[0], f[1], f[2]);
    }

private:
    template <class Fn> void get(const char* name, Fn& fn) {
        fn = reinterpret_cast<Fn>(dlsym(mLib, name));
        if (!fn) {
            throw std::runtime_error(std::string("stand-in HD library lacks ") + name);
        }
    }
    void* mLib = nullptr;
};

PhantomConfig fakeConfig(const std::string& deviceName) {
    PhantomConfig c;
    c.deviceName = deviceName;
    c.library = kFakeLibrary;
    return c;
}

bool near(const Vec3& a, const Vec3& b, double tolerance = 1e-12) {
    return glm::length(a - b) <= tolerance;
}

/// A command clock the test steps by hand (ns).
std::atomic<std::int64_t> gTestNowNs{1'000'000'000};
std::int64_t testClock() {
    return gTestNowNs.load();
}

/// Gives `dev` the hand-stepped command clock: while a test leaves it alone, a written force
/// never ages, so a test that writes once and then waits for the HD thread to apply it does
/// not race the command timeout (which has its own tests below).
PhantomDevice& withFrozenClock(PhantomDevice& dev) {
    dev.setCommandClock(&testClock);
    return dev;
}

} // namespace

TEST_CASE("a phantom opens by name or the default, and a wrong name is an error naming it",
          "[threads]") {
    FakeHd fake;
    {
        PhantomDevice dev("left", fakeConfig(""), 0.0);
        CHECK(dev.kind() == DeviceKind::Phantom);
        CHECK(dev.name() == "left");
        REQUIRE(dev.open() == DeviceStatus::Ok);
        CHECK(fake.isInitialised(kDefault) == 1);
        CHECK(fake.forceOutputEnabled(kDefault) == 1);
        CHECK(dev.open() == DeviceStatus::Ok); // already open: no second hdInitDevice
        const DeviceCapabilities caps = dev.capabilities();
        CHECK(caps.model == "Fake Touch");
        CHECK(caps.maxForceN == Approx(3.3));          // HD_NOMINAL_MAX_FORCE, N
        CHECK(caps.maxStiffness == Approx(1260.0));    // 1.26 N/mm -> N/m
        CHECK(caps.workspace.min.x == Approx(-0.080)); // mm -> m
        CHECK(caps.workspace.max.z == Approx(0.035));
        dev.close();
        CHECK(fake.isInitialised(kDefault) == 0);
    }
    {
        PhantomDevice dev("right", fakeConfig("Right Touch"), 2.0);
        REQUIRE(dev.open() == DeviceStatus::Ok);
        CHECK(fake.isInitialised(kRight) == 1);
        CHECK(fake.isInitialised(kDefault) == 0);
        CHECK(dev.capabilities().maxForceN == Approx(2.0)); // the configured clamp is smaller
    }
    CHECK(fake.isInitialised(kRight) == 0); // the destructor closed it
    {
        PhantomDevice dev("left", fakeConfig("No Such Touch"), 0.0);
        CHECK(dev.open() == DeviceStatus::Error);
        const std::string msg = dev.errorMessage();
        CHECK_THAT(msg, Catch::Contains("No Such Touch"));
        CHECK_THAT(msg, Catch::Contains("\"left\""));
        CHECK_THAT(msg, Catch::Contains("HD_COMM_CONFIG_ERROR"));
        DeviceState s;
        CHECK(dev.read(s) == DeviceStatus::NotOpen);
        CHECK(dev.write(Vec3(1, 0, 0)) == DeviceStatus::NotOpen);
    }
    CHECK(fake.schedulerRunning() == 0);
    CHECK(fake.callbacksScheduled() == 0);
}

TEST_CASE("positions arrive in metres from the HD's millimetres, with velocity and buttons",
          "[threads]") {
    FakeHd fake;
    fake.setMotion(kDefault, 12.5, -40.0, 7.0, 0.0, 0.0, 0.0);
    fake.setButtons(kDefault, 0b10);
    PhantomDevice dev("left", fakeConfig(""), 0.0);
    REQUIRE(dev.open() == DeviceStatus::Ok);
    DeviceState s;
    REQUIRE(dev.read(s) == DeviceStatus::Ok);
    CHECK(near(s.position, Vec3(0.0125, -0.040, 0.007)));
    CHECK(s.hasVelocity);
    CHECK(near(s.velocity, Vec3(0.0)));
    CHECK(s.buttons == 0b10u);
    CHECK(s.sequence > 0);

    // Now move along x at 100 mm/s and z at -50 mm/s: velocity in m/s, x grows, y stays.
    fake.setMotion(kDefault, 12.5, -40.0, 7.0, 100.0, 0.0, -50.0);
    fake.setButtons(kDefault, 0b01);
    REQUIRE(eventually([&] {
        return dev.read(s) == DeviceStatus::Ok && near(s.velocity, Vec3(0.1, 0.0, -0.05));
    }));
    const std::uint64_t firstSequence = s.sequence;
    const double firstX = s.position.x;
    REQUIRE(eventually([&] {
        DeviceState t;
        return dev.read(t) == DeviceStatus::Ok && t.sequence > firstSequence + 5 &&
               t.position.x > firstX && t.position.z < 0.007 &&
               std::abs(t.position.y + 0.040) < 1e-12 && t.buttons == 0b01u;
    }));
}

TEST_CASE("the stylus orientation arrives from HD_CURRENT_TRANSFORM as a unit quaternion, with "
          "the gimbal angles",
          "[threads]") {
    FakeHd fake;
    fake.setMotion(kDefault, 10.0, 20.0, 30.0, 0.0, 0.0, 0.0);
    PhantomDevice dev("left", fakeConfig(""), 0.0);
    REQUIRE(dev.open() == DeviceStatus::Ok);
    DeviceState s;
    REQUIRE(dev.read(s) == DeviceStatus::Ok);
    CHECK(s.hasOrientation);
    CHECK(s.hasGimbalAngles);
    CHECK_FALSE(s.hasAngularVelocity); // not read: its unit is not in the HD headers
    CHECK_FALSE(s.hasGripper);
    CHECK(near(s.orientation * Vec3(1, 2, 3), Vec3(1, 2, 3))); // identity at rest

    // A quarter turn about +z: the stylus's x axis points along the device's +y.
    const double quarter = std::acos(0.0);
    fake.setStylus(kDefault, 0.0, 0.0, 1.0, quarter, 0.1, -0.2, 0.3);
    REQUIRE(eventually([&] {
        return dev.read(s) == DeviceStatus::Ok && near(s.gimbalAnglesRad, Vec3(0.1, -0.2, 0.3));
    }));
    CHECK(near(s.orientation * Vec3(1, 0, 0), Vec3(0, 1, 0), 1e-12));
    CHECK(near(s.orientation * Vec3(0, 0, 1), Vec3(0, 0, 1), 1e-12));
    CHECK(std::abs(glm::length(s.orientation) - 1.0) < 1e-12);
    CHECK(near(s.position, Vec3(0.010, 0.020, 0.030)));

    // An arbitrary turn: the quaternion rotates like the matrix the HD library built.
    const Vec3 axis = glm::normalize(Vec3(1.0, -2.0, 0.5));
    fake.setStylus(kDefault, axis.x, axis.y, axis.z, 2.0, 0.0, 0.0, 0.0);
    REQUIRE(eventually(
        [&] { return dev.read(s) == DeviceStatus::Ok && near(s.gimbalAnglesRad, Vec3(0.0)); }));
    const Quat expected = glm::angleAxis(2.0, axis);
    for (const Vec3& v : {Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.3, -0.4, 2.0)}) {
        CHECK(near(s.orientation * v, expected * v, 1e-12));
    }
}

TEST_CASE("forces arrive in newtons, clamped to the limit, and are zero after close", "[threads]") {
    FakeHd fake;
    PhantomDevice dev("left", fakeConfig("Left Touch"), 2.0);
    withFrozenClock(dev);
    REQUIRE(dev.open() == DeviceStatus::Ok);
    CHECK(near(fake.force(kLeft), Vec3(0.0))); // open applies zero force

    REQUIRE(dev.write(Vec3(1.0, -0.5, 0.25)) == DeviceStatus::Ok);
    CHECK(eventually([&] { return near(fake.force(kLeft), Vec3(1.0, -0.5, 0.25)); }));

    // 5 N along y exceeds the 2 N limit: the device gets 2 N along y.
    REQUIRE(dev.write(Vec3(0.0, 5.0, 0.0)) == DeviceStatus::Ok);
    CHECK(eventually([&] { return near(fake.force(kLeft), Vec3(0.0, 2.0, 0.0), 1e-9); }));
    CHECK(fake.maxForceSeen(kLeft) <= 2.0 + 1e-9);

    // A non-finite force is refused and zero is applied instead.
    CHECK(dev.write(Vec3(std::nan(""), 0.0, 0.0)) == DeviceStatus::BadData);
    CHECK(eventually([&] { return near(fake.force(kLeft), Vec3(0.0)); }));

    REQUIRE(dev.write(Vec3(0.0, 0.0, 1.5)) == DeviceStatus::Ok);
    REQUIRE(eventually([&] { return near(fake.force(kLeft), Vec3(0.0, 0.0, 1.5)); }));
    const unsigned long long framesBeforeClose = fake.forceFrames(kLeft);
    dev.close();
    // The last frame before hdDisableDevice applied zero (the fake keeps it after the release).
    CHECK(fake.forceFrames(kLeft) > framesBeforeClose);
    CHECK(near(fake.force(kLeft), Vec3(0.0)));
    CHECK(fake.isInitialised(kLeft) == 0);
    CHECK(fake.forceOutputEnabled(kLeft) == 0);
    CHECK(fake.schedulerRunning() == 0);
    CHECK(dev.write(Vec3(1, 0, 0)) == DeviceStatus::NotOpen);
    dev.close(); // twice is safe
}

TEST_CASE("two phantoms share one HD scheduler and each gets its own force", "[threads]") {
    FakeHd fake;
    fake.setMotion(kLeft, -100.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    fake.setMotion(kRight, 100.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    PhantomDevice left("left", fakeConfig("Left Touch"), 0.0);
    PhantomDevice right("right", fakeConfig("Right Touch"), 0.0);
    withFrozenClock(left);
    withFrozenClock(right);
    REQUIRE(left.open() == DeviceStatus::Ok);
    REQUIRE(right.open() == DeviceStatus::Ok);
    CHECK(fake.initWhileRunning() == 0); // the scheduler was paused around hdInitDevice
    CHECK(fake.callbacksScheduled() == 2);
    // Both devices are framed within one tick of the one scheduler thread.
    CHECK(eventually([&] { return fake.maxDevicesPerTick() == 2; }));

    DeviceState l, r;
    REQUIRE(eventually([&] { return left.read(l) == DeviceStatus::Ok; }));
    REQUIRE(eventually([&] { return right.read(r) == DeviceStatus::Ok; }));
    CHECK(near(l.position, Vec3(-0.1, 0.0, 0.0)));
    CHECK(near(r.position, Vec3(0.1, 0.0, 0.0)));

    REQUIRE(left.write(Vec3(1.0, 0.0, 0.0)) == DeviceStatus::Ok);
    REQUIRE(right.write(Vec3(0.0, -2.0, 0.0)) == DeviceStatus::Ok);
    CHECK(eventually([&] {
        return near(fake.force(kLeft), Vec3(1.0, 0.0, 0.0)) &&
               near(fake.force(kRight), Vec3(0.0, -2.0, 0.0));
    }));

    // Closing one leaves the other running on the same scheduler.
    left.close();
    CHECK(fake.schedulerRunning() == 1);
    CHECK(fake.callbacksScheduled() == 1);
    CHECK(near(fake.force(kLeft), Vec3(0.0)));
    REQUIRE(right.write(Vec3(0.0, 0.0, 0.5)) == DeviceStatus::Ok);
    CHECK(eventually([&] { return near(fake.force(kRight), Vec3(0.0, 0.0, 0.5)); }));
    CHECK(eventually([&] { return right.read(r) == DeviceStatus::Ok; }));
    right.close();
    CHECK(fake.schedulerRunning() == 0);
}

TEST_CASE("an HD error in the scheduler becomes a fault with the HD code and text", "[threads]") {
    FakeHd fake;
    PhantomDevice dev("left", fakeConfig(""), 0.0);
    withFrozenClock(dev);
    REQUIRE(dev.open() == DeviceStatus::Ok);
    REQUIRE(dev.write(Vec3(0.5, 0.0, 0.0)) == DeviceStatus::Ok);
    REQUIRE(eventually([&] { return near(fake.force(kDefault), Vec3(0.5, 0.0, 0.0)); }));

    fake.injectError(kDefault, 0x0300 /* HD_DEVICE_FAULT */, 42);
    DeviceState s;
    REQUIRE(eventually([&] { return dev.read(s) == DeviceStatus::Error; }));
    CHECK(dev.write(Vec3(0.5, 0.0, 0.0)) == DeviceStatus::Error);
    const std::string msg = dev.errorMessage();
    CHECK_THAT(msg, Catch::Contains("0x0300"));
    CHECK_THAT(msg, Catch::Contains("HD_DEVICE_FAULT"));
    CHECK_THAT(msg, Catch::Contains("Device fault (fake)")); // hdGetErrorString's text
    CHECK_THAT(msg, Catch::Contains("42"));
    // A faulted device applies zero force.
    CHECK(eventually([&] { return near(fake.force(kDefault), Vec3(0.0)); }));
    dev.close();
    CHECK_THAT(dev.errorMessage(), Catch::Contains("HD_DEVICE_FAULT")); // kept after close

    // Reopening clears the fault.
    REQUIRE(dev.open() == DeviceStatus::Ok);
    CHECK(dev.read(s) == DeviceStatus::Ok);
}

TEST_CASE("an unplugged phantom reads Disconnected", "[threads]") {
    FakeHd fake;
    PhantomDevice dev("left", fakeConfig(""), 0.0);
    REQUIRE(dev.open() == DeviceStatus::Ok);
    fake.removeDevice(kDefault);
    DeviceState s;
    REQUIRE(eventually([&] { return dev.read(s) == DeviceStatus::Disconnected; }));
    CHECK_THAT(dev.errorMessage(), Catch::Contains("HD_COMM_ERROR"));
    CHECK_THAT(dev.errorMessage(), Catch::Contains("cable"));
}

TEST_CASE("a stalled HD scheduler makes read() report Stalled, and close() still returns",
          "[threads]") {
    FakeHd fake;
    PhantomDevice dev("left", fakeConfig(""), 0.0);
    dev.setStaleTimeout(std::chrono::milliseconds(20));
    REQUIRE(dev.open() == DeviceStatus::Ok);
    DeviceState s;
    REQUIRE(eventually([&] { return dev.read(s) == DeviceStatus::Ok; }));

    fake.stall(1);
    REQUIRE(eventually([&] { return dev.read(s) == DeviceStatus::Stalled; }));
    CHECK(dev.read(s) == DeviceStatus::Stalled); // no newer sample: counted as a stale read
    CHECK(dev.staleSampleCount() > 0);
    fake.stall(0);
    REQUIRE(eventually([&] { return dev.read(s) == DeviceStatus::Ok; }));

    fake.stall(1);
    dev.close(); // gives up waiting for the zero-force tick, releases the device anyway
    CHECK(fake.isInitialised(kDefault) == 0);
    CHECK(fake.callbacksScheduled() == 0);
    CHECK_THAT(dev.errorMessage(), Catch::Contains("not confirmed"));
}

TEST_CASE("a missing HD library is a clear error and probePhantoms says why") {
    const std::string missing = "/nonexistent/hapto/libHD.so";
    PhantomConfig config;
    config.library = missing;
    PhantomDevice dev("left", config, 0.0);
    CHECK(dev.open() == DeviceStatus::Error);
    CHECK_THAT(dev.errorMessage(), Catch::Contains("not found"));
    CHECK_THAT(dev.errorMessage(), Catch::Contains("install OpenHaptics"));
    CHECK_THAT(dev.errorMessage(), Catch::Contains(missing));

    std::string why;
    const std::vector<PhantomInfo> found = probePhantoms(missing, why);
    CHECK(found.empty());
    CHECK_THAT(why, Catch::Contains("OpenHaptics"));
    CHECK_THAT(why, Catch::Contains("not found: install OpenHaptics from 3D Systems; hapto loads "
                                    "it at run time"));

    // A library that is not libHD at all is named as such.
    const std::vector<PhantomInfo> none = probePhantoms("libc.so.6", why);
    CHECK(none.empty());
    CHECK_THAT(why, Catch::Contains("not a usable OpenHaptics HD library"));
}

TEST_CASE("probePhantoms lists the stand-in's default device", "[threads]") {
    FakeHd fake;
    std::string why;
    const std::vector<PhantomInfo> found = probePhantoms(kFakeLibrary, why);
    REQUIRE(found.size() == 1);
    CHECK(why.empty());
    CHECK(found[0].deviceName.empty());
    CHECK(found[0].model == "Fake Touch");
    CHECK(found[0].serial == "FAKE-0001");
    CHECK(found[0].maxForceN == Approx(3.3));
    CHECK(found[0].workspace.max.x == Approx(0.080));
    CHECK(fake.isInitialised(kDefault) == 0); // the probe released it

    // While a phantom of that library is open, the probe refuses instead of interfering.
    PhantomDevice dev("left", fakeConfig(""), 0.0);
    REQUIRE(dev.open() == DeviceStatus::Ok);
    CHECK(probePhantoms(kFakeLibrary, why).empty());
    CHECK_THAT(why, Catch::Contains("in use"));
}

TEST_CASE("a phantom whose servo stops writing applies zero force once the newest command is "
          "older than the command timeout (stepped HD ticks and clock)",
          "[threads]") {
    FakeHd fake;
    PhantomConfig config = fakeConfig("Left Touch");
    config.commandTimeoutMs = 3.0;
    PhantomDevice dev("left", config, 0.0);
    const std::int64_t t0 = 7'000'000'000;
    gTestNowNs = t0;
    dev.setCommandClock(&testClock);
    REQUIRE(dev.open() == DeviceStatus::Ok);
    fake.stall(1); // from here on only fake.step runs HD ticks, on this thread

    const Vec3 force(1.0, -0.5, 0.25);
    REQUIRE(dev.write(force) == DeviceStatus::Ok); // stamped t0; then the servo stalls
    fake.step(1);
    CHECK(near(fake.force(kLeft), force));
    // Exactly as old as the timeout: the HD callback keeps applying it.
    gTestNowNs = t0 + 3'000'000;
    for (int tick = 0; tick < 20; ++tick) {
        fake.step(1);
        INFO("tick " << tick);
        CHECK(near(fake.force(kLeft), force));
    }
    // One nanosecond older: the very next tick applies zero, and every tick after it.
    gTestNowNs = t0 + 3'000'001;
    for (int tick = 0; tick < 20; ++tick) {
        fake.step(1);
        INFO("tick " << tick);
        CHECK(near(fake.force(kLeft), Vec3(0.0)));
    }
    // Reading goes on as before, and a fresh write brings the force back at once.
    DeviceState s;
    CHECK(dev.read(s) == DeviceStatus::Ok);
    REQUIRE(dev.write(Vec3(0.0, 0.0, 0.5)) == DeviceStatus::Ok);
    fake.step(1);
    CHECK(near(fake.force(kLeft), Vec3(0.0, 0.0, 0.5)));
    fake.stall(0);
    dev.close();
    CHECK(near(fake.force(kLeft), Vec3(0.0)));
    gTestNowNs = 1'000'000'000;
}

TEST_CASE("a phantom whose servo thread stops feels no force (steady clock)", "[realtime]") {
    FakeHd fake;
    PhantomConfig config = fakeConfig("");
    config.commandTimeoutMs = 2.0;
    PhantomDevice dev("left", config, 0.0);
    REQUIRE(dev.open() == DeviceStatus::Ok);
    // A servo that writes until the force is seen applied, then stops for good.
    std::atomic<bool> applied{false};
    std::thread servo([&] {
        const auto guard = std::chrono::steady_clock::now() + std::chrono::seconds(10);
        while (!applied.load() && std::chrono::steady_clock::now() < guard) {
            (void)dev.write(Vec3(0.5, 0.0, 0.0));
            std::this_thread::sleep_for(std::chrono::microseconds(200));
        }
    });
    CHECK(eventually([&] {
        const bool on = near(fake.force(kDefault), Vec3(0.5, 0.0, 0.0));
        if (on) {
            applied = true;
        }
        return on;
    }));
    applied = true;
    servo.join();
    // Only the eventual zero is asserted, within the generous bound of waitFor (10 s).
    CHECK(eventually([&] { return near(fake.force(kDefault), Vec3(0.0)); }));
    dev.close();
}
