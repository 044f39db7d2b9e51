#pragma once
/// The statistics across repeats every experiment reports, and the one parser of sweep lists.
///
/// Design note. A cell of an experiment is run `repeats` times; the figure reported is the
/// median over the repeats and its spread a distribution-free 95 % confidence interval for the
/// median from order statistics: with the n values sorted, x(1) <= ... <= x(n), the interval
/// [x(j), x(n+1-j)] holds the true median with probability P(j <= B <= n - j), B ~
/// Binomial(n, 1/2), whatever the distribution of the values (continuous). j is the largest
/// rank whose coverage reaches the level asked (Conover, "Practical Nonparametric Statistics",
/// 3rd ed., section 3.2, the confidence interval for a quantile; also Hollander & Wolfe,
/// "Nonparametric Statistical Methods", the sign-test interval). Below 6 repeats no pair of
/// ranks reaches 95 %: the interval is then [min, max] and `coverage` says what it holds (5
/// runs: 93.75 %, 3: 75 %, 1: 0 %). The coverage is exact for that rule, not an asymptotic one.
///
/// Sweep lists (device counts, object counts, rates) are all read by parseSweepList: items
/// separated by commas, each a number, a range A-B or A:B (every whole number from A to B) or
/// A:B:S (A, A + S, ... up to B); a bad item is refused naming the option and the item.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace hapto::experiments {

/// The median of repeats and its order-statistic confidence interval.
struct MedianInterval {
    double median = 0;    ///< The sample median (mean of the two middle values when n is even).
    double lo = 0;        ///< The interval's lower end, x(j).
    double hi = 0;        ///< The interval's upper end, x(n+1-j).
    double coverage = 0;  ///< P(the interval holds the true median), exact: 0..1.
    std::size_t n = 0;    ///< Values it was computed from (non-finite ones are dropped).
    std::size_t rank = 0; ///< j: the interval runs from the j-th smallest to the j-th largest.
};

/// The coverage of [x(j), x(n+1-j)] for the median of n values: P(j <= B <= n - j), B ~
/// Binomial(n, 1/2); 0 when 2j > n. [any thread]
double medianIntervalCoverage(std::size_t n, std::size_t j);

/// The median of `values` and the order-statistic interval of at least `level` coverage (or
/// [min, max] with its lower coverage when n is too small to reach it); non-finite values are
/// dropped; all zero when none is left. [any thread]
MedianInterval medianInterval(std::vector<double> values, double level = 0.95);

/// "1.23 [1.10, 1.40]": the median and the interval with `decimals` places. [any thread]
std::string intervalText(const MedianInterval& m, int decimals);

/// A sentence for reports: how the intervals were made and what coverage `repeats` runs give
/// ("95 % intervals ...", or "[min, max] of 3 runs: 75 % coverage"). [any thread]
std::string intervalNote(std::size_t repeats, double level = 0.95);

/// How parseSweepList checks each value.
struct SweepListRule {
    double min = 1;    ///< Smallest value allowed.
    double max = 1e9;  ///< Largest value allowed.
    bool whole = true; ///< Whole numbers only (counts); false: any finite number (rates).
    std::size_t maxItems = 10000; ///< Most values a list may expand to.
};

/// Parses a sweep list: comma-separated items, each N, A-B, A:B or A:B:S (whole-number ranges
/// step 1 unless S is given; a range of rates needs S). Values are kept in the order given,
/// repeats dropped. Throws InputError "OPTION 'TEXT': ..." naming the bad item and why (empty,
/// not a number, not whole, out of range, a range running backwards, too many). [any thread]
std::vector<double> parseSweepList(const std::string& text, const std::string& option,
                                   const SweepListRule& rule);

/// The text parseSweepList reads back as `values` ("1000,4000"; each number as csvNumber writes
/// it): how a list option shows its default. [any thread]
std::string sweepListText(const std::vector<double>& values);

/// parseSweepList for whole counts from `min` to `max`. [any thread]
std::vector<std::int64_t> parseCountList(const std::string& text, const std::string& option,
                                         double min, double max);

} // namespace hapto::experiments
