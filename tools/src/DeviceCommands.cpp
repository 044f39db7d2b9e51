// `hapto devices`: what hardware this machine can reach, and why not when it cannot.

#include "Commands.h"
#include "Options.h"

#include "hapto/devices/FalconDevice.h"
#include "hapto/devices/PhantomDevice.h"

#include <cstdio>
#include <memory>

namespace hapto::cli {

void addDeviceCommands(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "devices", "List the force-feedback hardware hapto finds (Novint Falcons over USB, "
                   "PHANToM / Touch devices through OpenHaptics); says why when it finds none");
    auto library = std::make_shared<std::string>("libHD.so");
    cmd->add_option("--hd-library", *library, "OpenHaptics HD library to probe")
        ->capture_default_str();
    setExamples(cmd, {"hapto devices", "hapto devices --hd-library /opt/OpenHaptics/lib/libHD.so"});
    cmd->callback([library] {
        std::string why;
        const std::vector<FalconInfo> falcons = listFalcons(why);
        std::printf("Novint Falcon (libusb, 0403:cb48):\n");
        if (falcons.empty()) {
            std::printf("  none: %s\n", why.c_str());
        }
        for (const FalconInfo& f : falcons) {
            std::printf(
                "  bus %d address %d serial %s   (\"falcon\": {\"bus\": %d, \"address\": %d})\n",
                f.bus, f.address, f.serial.empty() ? "(unreadable)" : f.serial.c_str(), f.bus,
                f.address);
        }
        why.clear();
        const std::vector<PhantomInfo> phantoms = probePhantoms(*library, why);
        std::printf("PHANToM / Touch (OpenHaptics %s):\n", library->c_str());
        if (phantoms.empty()) {
            std::printf("  none: %s\n", why.c_str());
        }
        for (const PhantomInfo& p : phantoms) {
            const Vec3 size = p.workspace.size();
            std::printf("  %s: %s %s, serial %s, max force %.2f N, stiffness %.0f N/m, "
                        "workspace %.0f x %.0f x %.0f mm\n",
                        p.deviceName.empty() ? "(default device)" : p.deviceName.c_str(),
                        p.vendor.c_str(), p.model.c_str(), p.serial.c_str(), p.maxForceN,
                        p.maxStiffness, size.x * 1e3, size.y * 1e3, size.z * 1e3);
        }
        std::printf("Simulated devices (\"kind\": \"sim\") and replays (\"kind\": \"replay\") "
                    "are always available.\n");
    });
}

} // namespace hapto::cli
