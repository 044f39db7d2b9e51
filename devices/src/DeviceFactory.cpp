#include "hapto/devices/DeviceFactory.h"

#include "hapto/devices/FalconDevice.h"
#include "hapto/devices/PhantomDevice.h"
#include "hapto/devices/ReplayDevice.h"
#include "hapto/devices/SimDevice.h"
#include "hapto/io/InputError.h"

namespace hapto {

std::unique_ptr<Device> makeDevice(const DeviceConfig& config, const Scene& scene) {
    switch (config.kind) {
    case DeviceKind::Sim:
        return std::make_unique<SimDevice>(config, scene);
    case DeviceKind::Replay:
        return std::make_unique<ReplayDevice>(config);
    case DeviceKind::Falcon:
        return std::make_unique<FalconDevice>(config.name, std::get<FalconConfig>(config.params),
                                              config.maxForceN);
    case DeviceKind::Phantom: {
        auto device = std::make_unique<PhantomDevice>(
            config.name, std::get<PhantomConfig>(config.params), config.maxForceN);
        // One HD scheduler tick per servo tick keeps the exchange latency at one period.
        device->setSchedulerRateHz(static_cast<unsigned long>(config.rateHz));
        return device;
    }
    case DeviceKind::Scripted:
        break;
    }
    throw InputError("device '" + config.name + "': kind \"" + std::string(name(config.kind)) +
                     "\" is made by the program, not by makeDevice (expected sim, replay, falcon "
                     "or phantom)");
}

} // namespace hapto
