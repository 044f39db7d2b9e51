#pragma once
/// The one check every numeric command-line option goes through: a finite number in a range.

#include <CLI/CLI.hpp>

namespace hapto::cli {

/// The largest seed option value: the largest 64-bit unsigned integer, for finiteRange.
inline constexpr double kMaxSeed = 18446744073709551615.0;
/// The largest `--max-index-mb` (MB): 2^40, a limit no machine reaches.
inline constexpr double kMaxIndexMbOption = 1099511627776.0;

/// A CLI11 check for a number from `lo` to `hi` (inclusive). It refuses NaN, infinities, text
/// that is not a number and values out of range, naming the value and the range allowed; the
/// option's name is added by CLI11, and main() turns the refusal into exit code 2. Use it on
/// every numeric option (integers too: it also catches "-1" given to an unsigned option, which
/// CLI11 would otherwise wrap round). [control]
CLI::Validator finiteRange(double lo, double hi);

} // namespace hapto::cli
