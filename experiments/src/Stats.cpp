// The median and its order-statistic interval across repeats, and the sweep-list parser.

#include "hapto/experiments/Stats.h"
#include "hapto/experiments/Table.h"

#include "hapto/io/InputError.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace hapto::experiments {

double medianIntervalCoverage(std::size_t n, std::size_t j) {
    if (j == 0 || 2 * j > n) {
        return 0.0;
    }
    // P(j <= B <= n - j) for B ~ Binomial(n, 1/2): each term C(n, i) / 2^n through lgamma, exact
    // to double precision for the repeat counts an experiment takes.
    const double nd = static_cast<double>(n);
    double sum = 0.0;
    for (std::size_t i = j; i <= n - j; ++i) {
        const double id = static_cast<double>(i);
        sum += std::exp(std::lgamma(nd + 1) - std::lgamma(id + 1) - std::lgamma(nd - id + 1) -
                        nd * std::log(2.0));
    }
    return std::min(1.0, sum);
}

MedianInterval medianInterval(std::vector<double> values, double level) {
    std::erase_if(values, [](double v) { return !std::isfinite(v); });
    MedianInterval m;
    m.n = values.size();
    if (values.empty()) {
        return m;
    }
    std::sort(values.begin(), values.end());
    const std::size_t n = values.size();
    m.median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
    // The largest rank j whose interval still reaches the level; j = 1 ([min, max]) when none does.
    std::size_t j = 1;
    while (2 * (j + 1) <= n && medianIntervalCoverage(n, j + 1) >= level) {
        ++j;
    }
    m.rank = j;
    m.lo = values[j - 1];
    m.hi = values[n - j];
    m.coverage = medianIntervalCoverage(n, j);
    return m;
}

namespace {

std::string fixed(double v, int decimals) {
    char text[64];
    std::snprintf(text, sizeof text, "%.*f", decimals, v);
    return text;
}

std::string percent(double fraction) {
    char text[32];
    std::snprintf(text, sizeof text, "%.4g %%", 100.0 * fraction);
    return text;
}

} // namespace

std::string intervalText(const MedianInterval& m, int decimals) {
    if (m.n == 0) {
        return "-";
    }
    return fixed(m.median, decimals) + " [" + fixed(m.lo, decimals) + ", " + fixed(m.hi, decimals) +
           "]";
}

std::string intervalNote(std::size_t repeats, double level) {
    const std::string runs = std::to_string(repeats) + " run" + (repeats == 1 ? "" : "s");
    const double coverage = medianInterval(std::vector<double>(repeats, 0.0), level).coverage;
    const std::string method = "the median over " + runs +
                               " and, in brackets, a distribution-free interval for it "
                               "from order statistics (Binomial(n, 1/2) ranks)";
    if (repeats <= 1) {
        return "Each cell is one run: no interval (it would hold the median with probability "
               "0); use --repeats 6 or more for 95 % intervals.";
    }
    if (coverage < level) {
        return "Each figure is " + method + ": with " + runs + " it is [min, max], which holds " +
               "the true median with probability " + percent(coverage) + " only (95 % needs 6 " +
               "runs or more).";
    }
    return "Each figure is " + method + ", of coverage " + percent(coverage) + " (at least " +
           percent(level) + ").";
}

namespace {

/// `s` without spaces and tabs at either end.
std::string trimmed(const std::string& s) {
    const auto b = s.find_first_not_of(" \t");
    if (b == std::string::npos) {
        return {};
    }
    return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

/// Splits at every `sep`.
std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    for (std::size_t i = 0; i <= s.size(); ++i) {
        if (i == s.size() || s[i] == sep) {
            parts.push_back(trimmed(s.substr(start, i - start)));
            start = i + 1;
        }
    }
    return parts;
}

/// Where a range's '-' is: the first '-' after the first character that is not an exponent's.
std::size_t rangeDash(const std::string& item) {
    for (std::size_t i = 1; i < item.size(); ++i) {
        if (item[i] == '-' && item[i - 1] != 'e' && item[i - 1] != 'E') {
            return i;
        }
    }
    return std::string::npos;
}

class ListParser {
public:
    ListParser(const std::string& text, const std::string& option, const SweepListRule& rule)
        : mText(text), mOption(option), mRule(rule) {}

    [[noreturn]] void fail(const std::string& why) const {
        throw InputError(mOption + " '" + mText + "': " + why);
    }

    /// One number of an item, checked finite, whole when asked, and in range.
    double number(const std::string& part, const std::string& item, bool isStep = false) const {
        char* end = nullptr;
        const double v = part.empty() ? 0.0 : std::strtod(part.c_str(), &end);
        if (part.empty() || end != part.c_str() + part.size() || !std::isfinite(v)) {
            fail("'" + part + "' in '" + item + "' is not a number");
        }
        if (mRule.whole && v != std::floor(v)) {
            fail("'" + part + "' in '" + item + "' is not a whole number");
        }
        if (isStep) {
            if (v <= 0) {
                fail("the step '" + part + "' in '" + item + "' must be above 0");
            }
        } else if (v < mRule.min || v > mRule.max) {
            fail("'" + part + "' in '" + item + "' is out of range (" + fixedOrG(mRule.min) +
                 " .. " + fixedOrG(mRule.max) + ")");
        }
        return v;
    }

    static std::string fixedOrG(double v) {
        char text[32];
        std::snprintf(text, sizeof text, "%g", v);
        return text;
    }

    void add(double v) {
        if (std::find(mValues.begin(), mValues.end(), v) == mValues.end()) {
            if (mValues.size() == mRule.maxItems) {
                fail("more than " + std::to_string(mRule.maxItems) + " values");
            }
            mValues.push_back(v);
        }
    }

    void range(const std::string& item, const std::string& a, const std::string& b,
               const std::string* step) {
        const double from = number(a, item);
        const double to = number(b, item);
        if (to < from) {
            fail("the range '" + item + "' runs backwards (write the smaller value first)");
        }
        if (!step && !mRule.whole) {
            fail("the range '" + item + "' needs a step: A:B:STEP (e.g. 1000:4000:1000)");
        }
        const double s = step ? number(*step, item, true) : 1.0;
        const double count = std::floor((to - from) / s + 1e-9) + 1;
        if (count > static_cast<double>(mRule.maxItems)) {
            fail("the range '" + item + "' has more than " + std::to_string(mRule.maxItems) +
                 " values");
        }
        for (double k = 0; k < count; ++k) {
            add(from + k * s);
        }
    }

    std::vector<double> parse() {
        if (trimmed(mText).empty()) {
            fail("empty list (expected e.g. 1,2,4 or 1-8)");
        }
        for (const std::string& item : split(mText, ',')) {
            if (item.empty()) {
                fail("an empty item (two commas, or one at an end)");
            }
            if (item.find(':') != std::string::npos) {
                const std::vector<std::string> p = split(item, ':');
                if (p.size() > 3) {
                    fail("'" + item + "' is not A:B or A:B:STEP");
                }
                range(item, p[0], p[1], p.size() == 3 ? &p[2] : nullptr);
            } else if (const std::size_t dash = rangeDash(item); dash != std::string::npos) {
                range(item, trimmed(item.substr(0, dash)), trimmed(item.substr(dash + 1)), nullptr);
            } else {
                add(number(item, item));
            }
        }
        return mValues;
    }

private:
    const std::string& mText;
    const std::string& mOption;
    SweepListRule mRule;
    std::vector<double> mValues;
};

} // namespace

std::vector<double> parseSweepList(const std::string& text, const std::string& option,
                                   const SweepListRule& rule) {
    return ListParser(text, option, rule).parse();
}

std::vector<std::int64_t> parseCountList(const std::string& text, const std::string& option,
                                         double min, double max) {
    std::vector<std::int64_t> counts;
    for (const double v : parseSweepList(text, option, {min, max, true})) {
        counts.push_back(static_cast<std::int64_t>(v));
    }
    return counts;
}

std::string sweepListText(const std::vector<double>& values) {
    std::string text;
    for (const double v : values) {
        text += (text.empty() ? "" : ",") + csvNumber(v);
    }
    return text;
}

} // namespace hapto::experiments
