#pragma once
/// The terminal side of `hapto run`: messages and the live view (one line per device, redrawn
/// every 250 ms), written to stderr from a thread of their own.

#include "hapto/runtime/Runtime.h"

#include <memory>
#include <string>
#include <thread>

namespace hapto::cli {

/// Writes to stderr from its own thread, so a terminal that blocks (paused with Ctrl-S, a
/// stalled ssh) blocks only that thread, never the session: the control thread hands it text
/// and goes on. [control]
class LiveLines {
public:
    /// `runtime` null: messages only, no live view.
    explicit LiveLines(const Runtime* runtime);
    /// Writes what is queued if the terminal takes it within 300 ms; a write still blocked
    /// then is left behind (its thread detached, touching nothing of the session).
    ~LiveLines();
    LiveLines(const LiveLines&) = delete;
    LiveLines& operator=(const LiveLines&) = delete;

    /// Queues a message (a whole line, newline included). [control]
    void say(std::string text);

private:
    struct Shared;
    std::shared_ptr<Shared> mShared;
    std::thread mThread;
};

} // namespace hapto::cli
