// LiveLines: the writing thread shares only the block below with the control thread. Once the
// session ends (`quit`), it no longer reads the runtime, so it may outlive it when detached.

#include "LiveLines.h"

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <vector>

namespace hapto::cli {

struct LiveLines::Shared {
    std::mutex mutex;
    std::condition_variable wake;
    std::string queued;
    bool quit = false;
    bool done = false;
};

LiveLines::LiveLines(const Runtime* runtime) : mShared(std::make_shared<Shared>()) {
    mThread = std::thread([runtime, shared = mShared] {
        bool drew = false;
        auto nextDraw = std::chrono::steady_clock::now() + std::chrono::milliseconds(250);
        std::unique_lock lock(shared->mutex);
        for (;;) {
            shared->wake.wait_until(lock, nextDraw,
                                    [&] { return shared->quit || !shared->queued.empty(); });
            std::string text;
            if (!shared->queued.empty()) {
                text = drew ? "\x1b[" + std::to_string(runtime->deviceCount()) + "A\x1b[J" : "";
                text += std::exchange(shared->queued, {});
                drew = false; // messages go above the live lines; redraw them below
            }
            const bool quit = shared->quit;
            // The deadline moves on with or without a runtime to draw: a deadline left in the
            // past made this loop spin (a whole core under --quiet or without a terminal).
            const bool due = std::chrono::steady_clock::now() >= nextDraw;
            if (due) {
                nextDraw += std::chrono::milliseconds(250);
            }
            if (!quit && runtime && due) {
                if (drew) {
                    text += "\x1b[" + std::to_string(runtime->deviceCount()) + "A";
                }
                for (std::size_t i = 0; i < runtime->deviceCount(); ++i) {
                    text += "\r\x1b[2K" + runtime->liveLine(i) + "\n";
                }
                drew = true;
            }
            lock.unlock();
            std::fwrite(text.data(), 1, text.size(), stderr); // may block: only this thread
            lock.lock();
            if (quit && shared->queued.empty()) {
                break;
            }
        }
        shared->done = true;
        shared->wake.notify_all();
    });
}

LiveLines::~LiveLines() {
    std::unique_lock lock(mShared->mutex);
    mShared->quit = true;
    mShared->wake.notify_all();
    if (mShared->wake.wait_for(lock, std::chrono::milliseconds(300),
                               [&] { return mShared->done; })) {
        lock.unlock();
        mThread.join();
    } else {
        lock.unlock();
        mThread.detach(); // blocked on the terminal; it ends with the process
    }
}

void LiveLines::say(std::string text) {
    std::lock_guard lock(mShared->mutex);
    mShared->queued += text;
    mShared->wake.notify_all();
}

} // namespace hapto::cli
