// A device's load over the last second (LoadWindow.h).

#include "hapto/view/LoadWindow.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hapto {

LoadWindow::LoadWindow(double periodNs, std::uint64_t windowNs, std::size_t capacity)
    : mPeriodNs(periodNs), mWindowNs(windowNs), mCopies(std::max<std::size_t>(capacity, 2)) {
    if (!(periodNs > 0)) {
        throw std::invalid_argument("LoadWindow: the servo period must be positive");
    }
}

WindowLoad LoadWindow::sample(const LoadHistogram& histogram, std::uint64_t nowNs) {
    Copy& newest = mCopies[mNext];
    newest.timeNs = nowNs;
    histogram.counts(newest.counts);
    mNext = (mNext + 1) % mCopies.size();
    mHeld = std::min(mHeld + 1, mCopies.size());

    // The oldest copy still inside the window (or the oldest held).
    const Copy* oldest = &newest;
    for (std::size_t back = 1; back < mHeld; ++back) {
        const Copy& c = mCopies[(mNext + mCopies.size() - 1 - back) % mCopies.size()];
        if (nowNs - c.timeNs > mWindowNs) {
            break;
        }
        oldest = &c;
    }
    WindowLoad w;
    w.spanS = static_cast<double>(nowNs - oldest->timeNs) * 1e-9;
    std::uint64_t total = 0;
    for (std::size_t i = 0; i < mDiff.size(); ++i) {
        // A counter read mid-record may lag its neighbours; never below zero.
        mDiff[i] = newest.counts[i] >= oldest->counts[i] ? newest.counts[i] - oldest->counts[i] : 0;
        total += mDiff[i];
    }
    w.ticks = total;
    if (total == 0) {
        return w;
    }
    const auto quantile = [&](double q) {
        const auto rank = std::max<std::uint64_t>(
            1, static_cast<std::uint64_t>(std::ceil(q * static_cast<double>(total))));
        std::uint64_t seen = 0;
        for (std::size_t i = 0; i < mDiff.size(); ++i) {
            seen += mDiff[i];
            if (seen >= rank) {
                return static_cast<double>(LoadHistogram::bucketUpper(static_cast<int>(i)));
            }
        }
        return 0.0;
    };
    w.p50 = quantile(0.50) / mPeriodNs;
    w.p999 = quantile(0.999) / mPeriodNs;
    return w;
}

} // namespace hapto
