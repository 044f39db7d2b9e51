#pragma once
/// `--view` for a session command: the web server and the live feed over a runtime, started
/// and stopped around the session.

#include "Options.h"

#include "hapto/view/LiveFeed.h"
#include "hapto/view/ViewServer.h"

#include <memory>

namespace hapto::cli {

/// Serves the live view of one session when `args.enabled`, and does nothing otherwise.
/// Construct after the Runtime (it names the devices), start() once the runtime runs, call
/// update() from the control loop, and let it go (or stop()) before the runtime stops.
class LiveView {
public:
    /// Binds the server (throws std::runtime_error when it cannot) and prints the page's
    /// address on stderr, with a warning when it is not loopback. [control]
    LiveView(const ViewArgs& args, const char* command, const Scene& scene, const Runtime& runtime);
    ~LiveView();
    /// Starts the feed. [control]
    void start();
    /// Hands the world's current poses to the feed (cheap when nothing moved). [control]
    void update(const World& world);
    /// Stops the feed and the server. [control]
    void stop();

private:
    std::unique_ptr<ViewServer> mServer;
    std::unique_ptr<LiveFeed> mFeed;
};

} // namespace hapto::cli
