#include "hapto/runtime/LoadHistogram.h"

#include <algorithm>
#include <cmath>

namespace hapto {

HistogramSummary LoadHistogram::summary() const noexcept {
    HistogramSummary s;
    std::array<std::uint64_t, kBuckets> counts;
    std::uint64_t total = 0;
    for (int i = 0; i < kBuckets; ++i) {
        counts[i] = mBuckets[i].load(std::memory_order_relaxed);
        total += counts[i];
    }
    s.count = total;
    if (total == 0) {
        return s;
    }
    const double max = static_cast<double>(mMax.load(std::memory_order_relaxed));
    s.max = max;
    s.mean = static_cast<double>(mSum.load(std::memory_order_relaxed)) /
             static_cast<double>(std::max<std::uint64_t>(1, count()));
    const auto quantile = [&](double q) {
        const auto rank = static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(total)));
        std::uint64_t seen = 0;
        for (int i = 0; i < kBuckets; ++i) {
            seen += counts[i];
            if (seen >= std::max<std::uint64_t>(rank, 1)) {
                return std::min(static_cast<double>(bucketUpper(i)), max);
            }
        }
        return max;
    };
    s.p50 = quantile(0.50);
    s.p99 = quantile(0.99);
    s.p999 = quantile(0.999);
    return s;
}

} // namespace hapto
