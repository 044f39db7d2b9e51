// The exported trace columns (TraceColumns.h): one table, read by the CSV writer here and by
// the Python module's read_trace.

#include "hapto/devices/TraceColumns.h"

#include <array>
#include <charconv>

namespace hapto {
namespace {

constexpr std::uint64_t flag(bool b) {
    return b ? 1 : 0;
}

using S = const TraceSample&;

/// An Integer column.
constexpr TraceColumn integer(std::string_view name, std::string_view what, std::uint32_t since,
                              std::uint64_t (*get)(S)) {
    return {name, what, TraceColumnType::Integer, since, get, nullptr};
}

/// A Real column.
constexpr TraceColumn real(std::string_view name, std::string_view what, std::uint32_t since,
                           double (*get)(S)) {
    return {name, what, TraceColumnType::Real, since, nullptr, get};
}

// Version 1 columns first (the order `hapto trace export` always wrote), then version 2's.
constexpr std::array kColumns = {
    integer("tick", "tick index since the session started", 1, [](S s) { return s.tick; }),
    integer("time_ns", "wake-up time since the session started (ns)", 1,
            [](S s) { return s.timeNs; }),
    real("x_m", "position read, device frame (m)", 1, [](S s) { return s.positionM.x; }),
    real("y_m", "position read, device frame (m)", 1, [](S s) { return s.positionM.y; }),
    real("z_m", "position read, device frame (m)", 1, [](S s) { return s.positionM.z; }),
    real("fx_n", "force written, device frame (N)", 1, [](S s) { return s.forceN.x; }),
    real("fy_n", "force written, device frame (N)", 1, [](S s) { return s.forceN.y; }),
    real("fz_n", "force written, device frame (N)", 1, [](S s) { return s.forceN.z; }),
    integer("compute_ns", "wake-up to force written (ns)", 1,
            [](S s) -> std::uint64_t { return s.computeNs; }),
    integer("io_ns", "device read + write (ns)", 1, [](S s) -> std::uint64_t { return s.ioNs; }),
    TraceColumn{"status", "the read's status", TraceColumnType::Status, 1,
                [](S s) { return static_cast<std::uint64_t>(s.status); }, nullptr},
    integer("buttons", "buttons read (bit mask)", 1,
            [](S s) -> std::uint64_t { return s.buttons; }),
    real("proxy_x_m", "god-object proxy, device frame (m)", 2, [](S s) { return s.proxyM.x; }),
    real("proxy_y_m", "god-object proxy, device frame (m)", 2, [](S s) { return s.proxyM.y; }),
    real("proxy_z_m", "god-object proxy, device frame (m)", 2, [](S s) { return s.proxyM.z; }),
    real("vx_mps", "velocity read, device frame (m/s)", 2, [](S s) { return s.velocityMps.x; }),
    real("vy_mps", "velocity read, device frame (m/s)", 2, [](S s) { return s.velocityMps.y; }),
    real("vz_mps", "velocity read, device frame (m/s)", 2, [](S s) { return s.velocityMps.z; }),
    real("qw", "stylus orientation, device frame (unit quaternion)", 2,
         [](S s) { return s.orientation.w; }),
    real("qx", "stylus orientation, device frame (unit quaternion)", 2,
         [](S s) { return s.orientation.x; }),
    real("qy", "stylus orientation, device frame (unit quaternion)", 2,
         [](S s) { return s.orientation.y; }),
    real("qz", "stylus orientation, device frame (unit quaternion)", 2,
         [](S s) { return s.orientation.z; }),
    real("wx_radps", "stylus angular velocity, device frame (rad/s)", 2,
         [](S s) { return s.angularVelocity.x; }),
    real("wy_radps", "stylus angular velocity, device frame (rad/s)", 2,
         [](S s) { return s.angularVelocity.y; }),
    real("wz_radps", "stylus angular velocity, device frame (rad/s)", 2,
         [](S s) { return s.angularVelocity.z; }),
    integer("contacts", "constraints the renderer held (0..3)", 2,
            [](S s) -> std::uint64_t { return s.contactCount; }),
    integer("has_velocity", "1: the device gave the velocity", 2,
            [](S s) { return flag(s.hasVelocity); }),
    integer("has_orientation", "1: the device gave the orientation", 2,
            [](S s) { return flag(s.hasOrientation); }),
    integer("has_angular_velocity", "1: the device gave the angular velocity", 2,
            [](S s) { return flag(s.hasAngularVelocity); }),
    integer("missed_deadline", "1: the tick's force came after its deadline", 2,
            [](S s) { return flag(s.missedDeadline); }),
};

constexpr std::size_t kVersion1Columns = 12;
static_assert(kColumns[kVersion1Columns - 1].sinceVersion == 1 &&
                  kColumns[kVersion1Columns].sinceVersion == 2,
              "version 1's columns come first");

void appendInteger(std::string& out, std::uint64_t v) {
    char buf[24];
    const auto res = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, res.ptr);
}

void appendReal(std::string& out, double v) {
    char buf[32];
    const auto res = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, res.ptr);
}

} // namespace

std::span<const TraceColumn> traceColumns(std::uint32_t version) {
    return {kColumns.data(), version >= 2 ? kColumns.size() : kVersion1Columns};
}

std::string traceCsvHeader(std::uint32_t version) {
    std::string out;
    for (const TraceColumn& c : traceColumns(version)) {
        if (!out.empty()) {
            out += ',';
        }
        out += c.name;
    }
    out += '\n';
    return out;
}

void appendTraceCsvRow(const TraceSample& sample, std::uint32_t version, std::string& out) {
    bool first = true;
    for (const TraceColumn& c : traceColumns(version)) {
        if (!first) {
            out += ',';
        }
        first = false;
        switch (c.type) {
        case TraceColumnType::Integer:
            appendInteger(out, c.integer(sample));
            break;
        case TraceColumnType::Real:
            appendReal(out, c.real(sample));
            break;
        case TraceColumnType::Status:
            out += statusName(sample.status);
            break;
        }
    }
    out += '\n';
}

} // namespace hapto
