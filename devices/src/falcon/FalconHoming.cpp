#include "FalconHoming.h"

#include <cstdio>
#include <thread>

namespace hapto::falcon {

bool homeFalcon(FalconIoThread& io, const std::string& deviceName,
                std::chrono::milliseconds timeout, std::string& error) {
    using Clock = std::chrono::steady_clock;
    using namespace std::chrono_literals;
    io.setHoming(true);
    io.setLeds(8); // red while homing
    const auto deadline = Clock::now() + timeout;
    bool prompted = false;
    const auto promptAt = Clock::now() + 500ms;
    while (Clock::now() < deadline) {
        IoSample s{};
        if (io.state() != IoState::Running) {
            io.setHoming(false);
            error = "device '" + deviceName + "': the Falcon went away during homing";
            return false;
        }
        if (io.newestSample(s) && s.homedMask == 0x7) {
            io.setHoming(false);
            io.setLeds(2); // green: ready
            return true;
        }
        if (!prompted && Clock::now() > promptAt) {
            std::fprintf(stderr,
                         "hapto: Falcon '%s': pull the grip all the way out, then push it "
                         "all the way in, to home it\n",
                         deviceName.c_str());
            prompted = true;
        }
        std::this_thread::sleep_for(2ms);
    }
    io.setHoming(false);
    IoSample s{};
    const bool any = io.newestSample(s);
    error = "device '" + deviceName + "': homing timed out after " +
            std::to_string(timeout.count() / 1000.0).substr(0, 4) + " s (homed flags " +
            (any ? std::to_string(s.homedMask) : "none") +
            " of 7): pull the grip all the way out and push it back in while hapto starts";
    return false;
}

} // namespace hapto::falcon
