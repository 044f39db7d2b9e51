// `hapto render`: one device point moved along a path through the haptic tick (HapticTick, the
// tick every servo thread and the runtime's step mode run), one CSV line per tick. How a user
// checks what a scene feels like, and how tests pin the renderer's behaviour.
//
// The ticks are experiments::renderPath's (RenderPath.h: the point in the world frame, no
// device, the renderer's force before effects and safety), the same that Python's
// hapto.render returns; this file only checks the arguments and writes the CSV. Numbers are
// written as the shortest decimal that reads back as the same double (std::to_chars), with -0
// written 0: nothing is lost, and the same input gives the same bytes.

#include "Commands.h"
#include "Options.h"

#include "hapto/experiments/RenderPath.h"
#include "hapto/index/IndexSpec.h"
#include "hapto/index/SpatialIndex.h"
#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/runtime/World.h"

#include <charconv>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace hapto::cli {
namespace {

struct RenderArgs {
    std::string scene;
    std::string path;
    std::string index; ///< Empty: defaultIndexSpec(scene).
    std::uint64_t maxIndexMb = IndexSpec::kDefaultMaxMegabytes;
    double rateHz = 1000.0;
    std::string output;
};

void appendNumber(std::string& line, double value) {
    char text[32];
    const auto [end, ec] = std::to_chars(text, text + sizeof text, value == 0.0 ? 0.0 : value);
    (void)ec; // 32 characters hold any double's shortest form
    line.append(text, end);
}

void appendVec(std::string& line, const Vec3& v) {
    for (int a = 0; a < 3; ++a) {
        line += ',';
        appendNumber(line, v[a]);
    }
}

void runRender(const RenderArgs& a) {
    // Every check before any work: outputs never over an input, a writable output.
    if (!a.output.empty()) {
        refuseSameFile(a.output, "-o", a.scene, "--scene");
        refuseSameFile(a.output, "-o", a.path, "--path");
        checkOutputFile(a.output, "-o");
    }
    // A given spec is checked before any file is read; the default needs the scene.
    std::optional<IndexSpec> given;
    if (!a.index.empty()) {
        given = IndexSpec::parse(a.index).withMaxMegabytes(a.maxIndexMb);
    }
    const std::vector<Vec3> path = readPoints(a.path, "path file");
    if (path.empty()) {
        throw InputError(a.path + ": no points; a path file holds one point x,y,z (m, world "
                                  "frame) per tick, e.g. 0,0.03,0");
    }
    Scene scene = loadSceneOrDefault(a.scene);
    const IndexSpec spec = given ? *given : sessionIndexSpec({}, scene, a.maxIndexMb);
    const World world(std::move(scene), spec);
    const WorldSnapshot& snapshot = world.current();

    TextOutput out(a.output);
    std::string& text = out.text();
    for (const std::string_view column : experiments::renderPathColumns()) {
        text += text.empty() ? "" : ",";
        text += column;
    }
    text += '\n';
    const std::vector<experiments::PathTick> ticks =
        experiments::renderPath(snapshot, path, a.rateHz);
    for (std::size_t i = 0; i < ticks.size(); ++i) {
        const experiments::PathTick& t = ticks[i];
        text += std::to_string(i);
        appendVec(text, t.pointM);
        appendVec(text, t.proxyM);
        appendVec(text, t.forceN);
        text += ',';
        text += std::to_string(t.contacts);
        text += '\n';
        out.afterRow();
    }
    out.finish();
}

} // namespace

void addRenderCommands(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "render", "Move one device point along a path through the haptic tick and print, per "
                  "tick, the point, the proxy, the renderer's force (N, before the safety "
                  "filter) and the contact count as CSV");
    auto a = std::make_shared<RenderArgs>();
    cmd->add_option("--scene", a->scene, "Scene file")->required();
    cmd->add_option("--path", a->path,
                    "CSV file, one device point x,y,z (m, world frame) per tick, optional header "
                    "x,y,z")
        ->required();
    addIndexOption(cmd, a->index);
    addMaxIndexMbOption(cmd, a->maxIndexMb);
    cmd->add_option("--rate", a->rateHz,
                    "Tick rate (Hz): dt for the velocity and the renderer's damping and friction")
        ->capture_default_str()
        ->check(finiteRange(100, 100000));
    cmd->add_option("-o,--output", a->output, "Output CSV file (default: standard output)");
    setExamples(cmd, {"hapto render --scene scene.json --path path.csv -o forces.csv",
                      "hapto render --scene mesh.json --path path.csv --rate 4000 --index grid:8"});
    cmd->callback([a] { runRender(*a); });
}

} // namespace hapto::cli
