#pragma once
/// Index memory limits, shared by the builders (internal).

#include "hapto/index/IndexSpec.h"

#include <cstdint>
#include <string>

namespace hapto::detail {

/// Throws IndexTooLargeError: "index SPEC would need about X MB (DETAIL), more than the Y MB
/// limit; ...". `atLeast` says the figure is a floor (an octree stopped part way). [control]
[[noreturn]] void refuseIndexMemory(const IndexSpec& spec, std::uint64_t bytes,
                                    const std::string& detail, bool atLeast = false);

} // namespace hapto::detail
