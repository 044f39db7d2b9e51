#pragma once
/// A one-line progress bar on stderr, drawn only when stderr is a terminal.

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <string>

namespace hapto::experiments {

/// Counts finished work units against a planned total and redraws at most 10 times a second.
/// Silent when stderr is not a terminal (tests, pipes, logs). [control]
class Progress {
public:
    /// `title` names the experiment; `total` is the planned number of units (it may grow).
    /// Draws on stderr when it is a terminal.
    Progress(std::string title, std::size_t total);
    /// Draws on `out` when `enabled` (tests: a temporary file). Notes go to `out` too.
    Progress(std::string title, std::size_t total, std::FILE* out, bool enabled);
    /// Erases the bar.
    ~Progress();
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    /// Adds planned units (a sweep discovering more work). [control]
    void addTotal(std::size_t units) { mTotal += units; }
    /// Marks `units` finished and shows `label` as the current work. [control]
    void advance(std::size_t units, const std::string& label);
    /// Shows `label` without finishing anything. [control]
    void show(const std::string& label) { advance(0, label); }
    /// Prints a line of text above the bar (always, terminal or not). [control]
    void note(const std::string& text);
    /// Erases the bar for good: call it before printing results, so that they never share a
    /// line with the bar. Later advances draw nothing; notes still print. [control]
    void finish();

private:
    void draw(bool force);
    void erase();

    std::FILE* mOut;
    std::string mTitle;
    std::string mLabel;
    std::size_t mTotal;
    std::size_t mDone = 0;
    bool mEnabled;
    bool mDrawn = false;
    std::chrono::steady_clock::time_point mStart;
    std::chrono::steady_clock::time_point mLastDraw;
};

} // namespace hapto::experiments
