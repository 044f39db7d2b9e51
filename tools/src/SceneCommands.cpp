// `hapto scene grid|random|cluster|default|info|mesh`.

#include "Commands.h"
#include "Options.h"

#include "hapto/scenes/Generators.h"
#include "hapto/scenes/InputError.h"
#include "hapto/scenes/MeshGenerators.h"
#include "hapto/scenes/OutputFile.h"
#include "hapto/scenes/SceneFile.h"

#include <nlohmann/json.hpp>

#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

namespace hapto::cli {

Scene loadSceneOrDefault(const std::string& path) {
    return path.empty() ? makeDefaultScene() : loadSceneFile(path);
}

namespace {

/// Refuses an output that cannot be written before the scene is generated. [control]
void checkSceneOutput(const std::string& out) {
    if (out != "-") {
        checkOutputFile(out, "-o");
    }
}

void writeScene(const Scene& scene, const std::string& out) {
    if (out == "-") {
        std::cout << sceneToJson(scene);
    } else {
        writeFileAtomically(out, sceneToJson(scene));
        std::cerr << "wrote " << scene.size() << " objects to " << out << "\n";
    }
}

void printInfo(const Scene& scene, const std::string& source, double loadSeconds) {
    std::size_t boxes = 0, rotated = 0;
    ObjectId minId = kMaxObjectId, maxId = 0;
    for (const SceneObject& o : scene.objects()) {
        boxes += o.shape == Shape::Box;
        rotated += o.shape == Shape::Box && o.rotation != Quat(1, 0, 0, 0);
        minId = std::min(minId, o.id);
        maxId = std::max(maxId, o.id);
    }
    const Aabb& b = scene.bounds();
    std::printf("scene:    %s\n", source.c_str());
    std::printf("objects:  %u (%zu boxes, %zu of them rotated; %zu spheres)\n", scene.size(), boxes,
                rotated, scene.size() - boxes);
    if (scene.size() > 0) {
        std::printf("ids:      %u .. %u\n", minId, maxId);
    }
    std::printf("bounds:   [%.4f, %.4f, %.4f] .. [%.4f, %.4f, %.4f] m\n", b.min.x, b.min.y, b.min.z,
                b.max.x, b.max.y, b.max.z);
    std::printf("loaded in %.3f s\n", loadSeconds);
}

/// `scene mesh`: the generated mesh goes to a binary PLY beside the scene file (F.json ->
/// F.ply), and the scene names it by "file" (format version 2). A PLY, not inline JSON: 10^7
/// triangles are about 190 MB of PLY against about 0.5 GB of JSON text, and a PLY is read
/// without a JSON parser holding the whole array. [control]
struct MeshSceneArgs {
    MeshOptions mesh;
    std::string shape = "sphere";
    std::string out;
};

std::filesystem::path meshFileFor(const std::filesystem::path& scene) {
    std::filesystem::path ply = scene;
    ply.replace_extension(".ply");
    return ply;
}

void appendShortest(std::string& out, double v) {
    char buf[32];
    const auto r = std::to_chars(buf, buf + sizeof buf, v == 0.0 ? 0.0 : v);
    out.append(buf, r.ptr);
}

void appendVec3(std::string& out, const Vec3& v) {
    out += '[';
    for (int a = 0; a < 3; ++a) {
        if (a > 0) {
            out += ", ";
        }
        appendShortest(out, v[a]);
    }
    out += ']';
}

/// The version 2 scene text for one mesh object read from `meshFile` (relative to the scene).
std::string meshSceneJson(const Scene& scene, const std::string& meshFile) {
    const SceneObject& o = scene.object(0);
    std::string out = "{\"format\": \"hapto-scene\", \"version\": 2,\n \"bounds\": {\"min\": ";
    appendVec3(out, scene.bounds().min);
    out += ", \"max\": ";
    appendVec3(out, scene.bounds().max);
    out += "},\n \"objects\": [\n  {\"id\": 0, \"shape\": \"mesh\", \"file\": ";
    out += nlohmann::json(meshFile).dump();
    out += ", \"center\": ";
    appendVec3(out, o.center);
    out += ", \"rotation\": [1, 0, 0, 0], \"scale\": 1, \"stiffness\": ";
    appendShortest(out, o.material.stiffness);
    out += ", \"friction\": [";
    appendShortest(out, o.material.staticFriction);
    out += ", ";
    appendShortest(out, o.material.dynamicFriction);
    out += "]}]}\n";
    return out;
}

void writeMeshScene(const MeshSceneArgs& args) {
    if (args.out == "-") {
        throw InputError("scene mesh: -o must name a file (the mesh is written beside it as a "
                         "PLY file), not '-'");
    }
    const std::filesystem::path out = args.out;
    const std::filesystem::path ply = meshFileFor(out);
    if (sameFile(out, ply)) {
        throw InputError("scene mesh: -o " + args.out +
                         " ends in .ply, where the mesh goes; name the scene file F.json");
    }
    checkOutputFile(out, "-o");
    checkOutputFile(ply, "-o (its mesh file " + ply.string() + ")");
    MeshOptions options = args.mesh;
    options.shape = *parseMeshShape(args.shape); // CLI11 checked the name
    const std::string meshFile = ply.filename().string();
    const Scene scene = makeMeshScene(options, MeshSource{meshFile, 1.0});
    const TriangleMesh& mesh = *scene.object(0).mesh;
    {
        AtomicOutputFile file(ply);
        writeMeshPly(mesh, file.stream());
        file.commit();
    }
    writeFileAtomically(out, meshSceneJson(scene, meshFile));
    std::cerr << "wrote a " << args.shape << " of " << mesh.triangleCount() << " triangles ("
              << mesh.vertices().size() << " vertices) to " << ply.string() << ", its scene to "
              << out.string() << "\n";
}

} // namespace

void addSceneCommands(CLI::App& app) {
    CLI::App* scene = app.add_subcommand("scene", "Generate scene files, or describe one");
    scene->require_subcommand(1);

    // grid
    {
        auto* cmd = scene->add_subcommand(
            "grid", "Experiment 1: K x K x K cubes on a regular lattice with gaps, bounds a little "
                    "larger than the lattice");
        auto opt = std::make_shared<LatticeOptions>();
        auto out = std::make_shared<std::string>();
        cmd->add_option("--per-side", opt->perSide, "K, cubes per lattice side")
            ->required()
            ->check(finiteRange(1, 100000));
        cmd->add_option("--size", opt->cubeSize, "Cube edge (m)")
            ->capture_default_str()
            ->check(finiteRange(1e-6, 1e3));
        cmd->add_option("--gap", opt->gap, "Free space between neighbouring cubes (m)")
            ->capture_default_str()
            ->check(finiteRange(0, 1e3));
        cmd->add_option("-o,--output", *out, "Output scene file ('-' for standard output)")
            ->required();
        cmd->callback([opt, out] {
            checkSceneOutput(*out);
            writeScene(makeLatticeScene(*opt), *out);
        });
    }
    // random
    {
        auto* cmd = scene->add_subcommand(
            "random", "Experiment 2: N cubes placed uniformly at random in a work cube centred on "
                      "the origin; bounds are the work cube");
        auto opt = std::make_shared<RandomOptions>();
        auto out = std::make_shared<std::string>();
        cmd->add_option("--count", opt->count, "Number of cubes (e.g. 200 or 1e6)")
            ->required()
            ->transform(wholeNumber(0, 4e9));
        cmd->add_option("--seed", opt->seed, "Random seed; same seed, same file")
            ->capture_default_str()
            ->check(finiteRange(0, kMaxSeed));
        cmd->add_option("--workspace", opt->workspace, "Edge of the work cube (m)")
            ->capture_default_str()
            ->check(finiteRange(1e-6, 1e4));
        cmd->add_option("--size", opt->cubeSize, "Cube edge (m)")
            ->capture_default_str()
            ->check(finiteRange(1e-6, 1e3));
        cmd->add_flag("--rotate", opt->rotate, "Give every cube a random orientation");
        cmd->add_option("--keep-clear", opt->keepClear,
                        "No object within this distance of the centre, where cursors start (m)")
            ->capture_default_str()
            ->check(finiteRange(0, 1e4));
        cmd->add_option("-o,--output", *out, "Output scene file ('-' for standard output)")
            ->required();
        cmd->callback([opt, out] {
            checkSceneOutput(*out);
            writeScene(makeRandomScene(*opt), *out);
        });
    }
    // cluster
    {
        auto* cmd = scene->add_subcommand(
            "cluster", "A strongly non-uniform scene: N cubes in C Gaussian clusters (a uniform "
                       "grid does badly here)");
        auto opt = std::make_shared<ClusterOptions>();
        auto out = std::make_shared<std::string>();
        cmd->add_option("--count", opt->count, "Number of cubes (e.g. 1e5)")
            ->required()
            ->transform(wholeNumber(0, 4e9));
        cmd->add_option("--clusters", opt->clusters, "Number of clusters")
            ->capture_default_str()
            ->check(finiteRange(1, 1000000));
        cmd->add_option("--seed", opt->seed, "Random seed; same seed, same file")
            ->capture_default_str()
            ->check(finiteRange(0, kMaxSeed));
        cmd->add_option("--workspace", opt->workspace, "Edge of the work cube (m)")
            ->capture_default_str()
            ->check(finiteRange(1e-6, 1e4));
        cmd->add_option("--size", opt->cubeSize, "Cube edge (m)")
            ->capture_default_str()
            ->check(finiteRange(1e-6, 1e3));
        cmd->add_option("--spread", opt->spread, "Standard deviation of each cluster (m)")
            ->capture_default_str()
            ->check(finiteRange(0, 1e4));
        cmd->add_flag("--rotate", opt->rotate, "Give every cube a random orientation");
        cmd->add_option("-o,--output", *out, "Output scene file ('-' for standard output)")
            ->required();
        cmd->callback([opt, out] {
            checkSceneOutput(*out);
            writeScene(makeClusterScene(*opt), *out);
        });
    }
    // default
    {
        auto* cmd = scene->add_subcommand(
            "default", "Write the embedded default scene (200 random 5 cm cubes, seed 2004, 4 cm "
                       "clear around the centre)");
        auto out = std::make_shared<std::string>();
        cmd->add_option("-o,--output", *out, "Output scene file ('-' for standard output)")
            ->required();
        cmd->callback([out] {
            checkSceneOutput(*out);
            writeScene(makeDefaultScene(), *out);
        });
    }
    // mesh
    {
        auto* cmd = scene->add_subcommand(
            "mesh", "A generated triangle mesh (geodesic sphere, torus or noise terrain) of about "
                    "N triangles, for load against triangle count: the scene file F.json and its "
                    "mesh F.ply beside it");
        auto args = std::make_shared<MeshSceneArgs>();
        cmd->add_option("--shape", args->shape, "sphere, torus or terrain")
            ->capture_default_str()
            ->check(CLI::IsMember({"sphere", "torus", "terrain"}));
        cmd->add_option("--triangles", args->mesh.triangles,
                        "About how many triangles (1e2 .. 1e7; the sphere has 20 f^2, within "
                        "1.5x of N, the others within 1.15x)")
            ->required()
            ->transform(wholeNumber(static_cast<double>(kMinGeneratedTriangles),
                                    static_cast<double>(kMaxGeneratedTriangles)));
        cmd->add_option("--size", args->mesh.size,
                        "Extent along x (m): sphere diameter, torus outer diameter, terrain edge")
            ->capture_default_str()
            ->check(finiteRange(1e-6, 1e3));
        cmd->add_option("--seed", args->mesh.seed, "Terrain noise seed; same seed, same files")
            ->capture_default_str()
            ->check(finiteRange(0, kMaxSeed));
        cmd->add_option("-o,--output", args->out, "Output scene file (the mesh goes to F.ply)")
            ->required();
        cmd->callback([args] { writeMeshScene(*args); });
    }
    // info
    {
        auto* cmd = scene->add_subcommand("info", "Load a scene (or the default) and describe it");
        auto path = std::make_shared<std::string>();
        cmd->add_option("--scene", *path, "Scene file (default: the embedded default scene)");
        cmd->callback([path] {
            const auto t0 = std::chrono::steady_clock::now();
            const Scene s = loadSceneOrDefault(*path);
            const double secs =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            printInfo(s, path->empty() ? "(embedded default scene)" : *path, secs);
        });
    }
}

} // namespace hapto::cli
