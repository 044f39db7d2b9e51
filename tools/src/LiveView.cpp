// `--view` for a session command (LiveView.h).

#include "LiveView.h"

#include <cstdio>

namespace hapto::cli {

LiveView::LiveView(const ViewArgs& args, const char* command, const Scene& scene,
                   const Runtime& runtime) {
    if (!args.enabled) {
        return;
    }
    ViewServerOptions options;
    options.bindAddress = args.bindAddress;
    options.port = args.port;
    mServer = std::make_unique<ViewServer>(options);
    mFeed = std::make_unique<LiveFeed>(runtime, *mServer);
    mServer->setDocument("/scene.json", viewSceneJson(scene, mFeed->devices(), ViewMode::Live));
    mServer->start();
    if (!isLoopbackAddress(args.bindAddress)) {
        std::fprintf(stderr,
                     "%s: warning: the view listens on %s, not on this machine only: anyone who "
                     "can reach port %d can watch this session (read-only)\n",
                     command, args.bindAddress.c_str(), mServer->port());
    }
    std::fprintf(stderr, "%s: view on %s\n", command, mServer->url().c_str());
    std::fflush(stderr);
}

LiveView::~LiveView() {
    stop();
}

void LiveView::start() {
    if (mFeed) {
        mFeed->start();
    }
}

void LiveView::update(const World& world) {
    if (mFeed) {
        mFeed->updatePoses(world.current());
        mFeed->updateLeaves(world.current());
    }
}

void LiveView::stop() {
    if (mFeed) {
        mFeed->stop();
    }
    if (mServer) {
        mServer->stop();
    }
}

} // namespace hapto::cli
