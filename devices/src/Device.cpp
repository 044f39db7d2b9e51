#include "hapto/devices/Device.h"

namespace hapto {

std::string_view statusName(DeviceStatus status) {
    switch (status) {
    case DeviceStatus::Ok:
        return "ok";
    case DeviceStatus::NotOpen:
        return "not-open";
    case DeviceStatus::Stalled:
        return "stalled";
    case DeviceStatus::Disconnected:
        return "disconnected";
    case DeviceStatus::BadData:
        return "bad-data";
    case DeviceStatus::Error:
        return "error";
    }
    return "unknown";
}

} // namespace hapto
