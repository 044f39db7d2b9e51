// The finite-range check for numeric options.

#include "Options.h"

#include <cmath>
#include <cstdio>
#include <string>

namespace hapto::cli {
namespace {

std::string number(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.15g", v);
    return text;
}

} // namespace

CLI::Validator finiteRange(double lo, double hi) {
    const std::string range = "from " + number(lo) + " to " + number(hi);
    return CLI::Validator(
        [lo, hi, range](std::string& text) -> std::string {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(text, v)) {
                return "'" + text + "' is not a number; expected a number " + range;
            }
            if (!std::isfinite(v)) {
                return "'" + text + "' is not a finite number; expected a number " + range;
            }
            if (v < lo || v > hi) {
                return text + " is out of range; expected a number " + range;
            }
            return {};
        },
        "in [" + number(lo) + ", " + number(hi) + "]", "FINITE_RANGE");
}

} // namespace hapto::cli
