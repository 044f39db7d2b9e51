// The progress bar of `hapto experiment`.

#include "hapto/experiments/Progress.h"

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace hapto::experiments {

Progress::Progress(std::string title, std::size_t total)
    : Progress(std::move(title), total, stderr, isatty(STDERR_FILENO) != 0) {}

Progress::Progress(std::string title, std::size_t total, std::FILE* out, bool enabled)
    : mOut(out), mTitle(std::move(title)), mTotal(total), mEnabled(enabled),
      mStart(std::chrono::steady_clock::now()), mLastDraw(mStart) {}

void Progress::finish() {
    erase();
    mEnabled = false;
}

Progress::~Progress() {
    erase();
}

void Progress::advance(std::size_t units, const std::string& label) {
    mDone += units;
    mLabel = label;
    draw(false);
}

void Progress::note(const std::string& text) {
    erase();
    std::fprintf(mOut, "%s\n", text.c_str());
    draw(true);
}

void Progress::erase() {
    if (mEnabled && mDrawn) {
        std::fprintf(mOut, "\r\x1b[2K");
        std::fflush(mOut);
        mDrawn = false;
    }
}

void Progress::draw(bool force) {
    if (!mEnabled) {
        return;
    }
    const auto now = std::chrono::steady_clock::now();
    if (!force && mDrawn && now - mLastDraw < std::chrono::milliseconds(100)) {
        return;
    }
    mLastDraw = now;
    constexpr int kWidth = 28;
    const double fraction =
        mTotal ? std::min(1.0, static_cast<double>(mDone) / static_cast<double>(mTotal)) : 0.0;
    const int filled = static_cast<int>(fraction * kWidth);
    const double elapsedS = std::chrono::duration<double>(now - mStart).count();
    std::string label = mLabel.size() > 44 ? mLabel.substr(0, 43) + "~" : mLabel;
    std::fprintf(mOut, "\r\x1b[2K%s [%s%s] %3.0f%% %5.0fs %s", mTitle.c_str(),
                 std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(kWidth - filled), '.').c_str(),
                 100.0 * fraction, elapsedS, label.c_str());
    std::fflush(mOut);
    mDrawn = true;
}

} // namespace hapto::experiments
