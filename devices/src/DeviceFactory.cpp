#include "hapto/devices/DeviceFactory.h"

#include "hapto/devices/FalconDevice.h"
#include "hapto/devices/PhantomDevice.h"
#include "hapto/devices/ReplayDevice.h"
#include "hapto/devices/SimDevice.h"
#include "hapto/scenes/InputError.h"

namespace hapto {

std::unique_ptr<Device> makeDevice(const DeviceConfig& config, const Scene& scene) {
    if (config.kind == "sim") {
        return std::make_unique<SimDevice>(config, scene);
    }
    if (config.kind == "replay") {
        return std::make_unique<ReplayDevice>(config);
    }
    if (config.kind == "falcon") {
        return std::make_unique<FalconDevice>(config.name, std::get<FalconConfig>(config.params),
                                              config.maxForceN);
    }
    if (config.kind == "phantom") {
        auto device = std::make_unique<PhantomDevice>(
            config.name, std::get<PhantomConfig>(config.params), config.maxForceN);
        // One HD scheduler tick per servo tick keeps the exchange latency at one period.
        device->setSchedulerRateHz(static_cast<unsigned long>(config.rateHz));
        return device;
    }
    throw InputError("device '" + config.name + "': unknown kind \"" + config.kind +
                     "\" (expected sim, replay, falcon or phantom)");
}

} // namespace hapto
