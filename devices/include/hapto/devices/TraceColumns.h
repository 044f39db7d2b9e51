#pragma once
/// The columns of an exported trace: one table that `hapto trace export` (CSV) and Python's
/// `hapto.read_trace` (numpy arrays) both read, so the two hold the same names and numbers.
///
/// Design note. A trace of version V exports the columns whose `sinceVersion` is at most V, in
/// the table's order: version 1 gives the first 12 (tick .. buttons), version 2 all 30 (proxy,
/// velocity, orientation, angular velocity, contact count and the four sample flags after
/// them). A column name carries its unit (`_m`, `_n`, `_ns`, `_mps`, `_radps`); a quaternion
/// component and a count have none. Each column reads its value from a TraceSample through a
/// plain function, so a new column is one row of the table. Integers are exact (u64); reals are
/// the recorded doubles, written in CSV as the shortest decimal that reads back as the same
/// double (std::to_chars). Fields a device did not give (see the has_* flags) export as the
/// trace stores them (zero velocity, the identity orientation).

#include "hapto/devices/TraceFormat.h"

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

namespace hapto {

/// What a trace column holds.
enum class TraceColumnType : std::uint8_t {
    Integer, ///< An unsigned integer (tick, ns, count, buttons, a 0/1 flag): exact.
    Real,    ///< A double (m, N, m/s, rad/s, a quaternion component).
    Status,  ///< The read's DeviceStatus, written as its name (statusName: "ok", ...).
};

/// One column of an exported trace.
struct TraceColumn {
    std::string_view name;        ///< CSV header name, with its unit ("x_m", "fx_n").
    std::string_view description; ///< What it is, one line (frame and unit).
    TraceColumnType type;         ///< How its values are read and written.
    std::uint32_t sinceVersion;   ///< The first trace version that records it (1 or 2).
    /// The value of an Integer column; of a Status column, the DeviceStatus's number.
    std::uint64_t (*integer)(const TraceSample&);
    /// The value of a Real column.
    double (*real)(const TraceSample&);
};

/// The columns a trace of format `version` holds, in export order (version 1: 12, version 2
/// and later: 30). [any thread]
std::span<const TraceColumn> traceColumns(std::uint32_t version);
/// The CSV header row for a trace of `version`: the column names joined by commas, then a
/// newline. [any thread]
std::string traceCsvHeader(std::uint32_t version);
/// Appends `sample`'s CSV row (newline included) for a trace of `version`. [any thread]
void appendTraceCsvRow(const TraceSample& sample, std::uint32_t version, std::string& out);

} // namespace hapto
