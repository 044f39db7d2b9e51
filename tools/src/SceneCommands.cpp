// `hapto scene grid|random|cluster|default|import|info|mesh|convert`.

#include "Commands.h"
#include "Options.h"

#include "hapto/io/InputError.h"
#include "hapto/io/OutputFile.h"
#include "hapto/scenes/BinaryScene.h"
#include "hapto/scenes/Generators.h"
#include "hapto/scenes/MeshFile.h"
#include "hapto/scenes/MeshGenerators.h"
#include "hapto/scenes/SceneFile.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <vector>

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

/// The most meshes `scene info` lists one by one (the totals count them all).
constexpr std::size_t kMeshesListed = 20;

/// "D degenerate and U duplicate dropped": the triangles a mesh's loading left out.
std::string droppedText(std::uint64_t degenerate, std::uint64_t duplicate) {
    return std::to_string(degenerate) + " degenerate and " + std::to_string(duplicate) +
           " duplicate dropped";
}

void printMeshLine(const SceneObject& o) {
    const TriangleMesh& m = *o.mesh;
    std::printf("  mesh %u: %u triangles, %s, %s, %s\n", o.id, m.triangleCount(),
                droppedText(m.droppedDegenerate(), m.droppedDuplicate()).c_str(),
                m.closed() ? "closed" : "open",
                m.source().file.empty() ? "inline" : ("file " + m.source().file).c_str());
}

void printInfo(const Scene& scene, const std::string& source, double loadSeconds) {
    std::size_t boxes = 0, rotated = 0, meshes = 0, closed = 0;
    std::uint64_t degenerate = 0, duplicate = 0;
    ObjectId minId = kMaxObjectId, maxId = 0;
    for (const SceneObject& o : scene.objects()) {
        boxes += o.shape == Shape::Box;
        rotated += o.shape == Shape::Box && o.rotation != Quat(1, 0, 0, 0);
        if (o.shape == Shape::Mesh) {
            ++meshes;
            closed += o.mesh->closed();
            degenerate += o.mesh->droppedDegenerate();
            duplicate += o.mesh->droppedDuplicate();
        }
        minId = std::min(minId, o.id);
        maxId = std::max(maxId, o.id);
    }
    const Aabb& b = scene.bounds();
    std::printf("scene:    %s\n", source.c_str());
    std::printf("objects:  %u (%zu boxes, %zu of them rotated; %zu spheres; %zu meshes)\n",
                scene.size(), boxes, rotated, scene.size() - boxes - meshes, meshes);
    if (scene.size() > 0) {
        std::printf("ids:      %u .. %u\n", minId, maxId);
    }
    std::printf("triangles: %u in %zu meshes (%zu closed, %zu open), %s\n", scene.triangleCount(),
                meshes, closed, meshes - closed, droppedText(degenerate, duplicate).c_str());
    std::size_t listed = 0;
    for (const SceneObject& o : scene.objects()) {
        if (o.shape == Shape::Mesh && listed++ < kMeshesListed) {
            printMeshLine(o);
        }
    }
    if (listed > kMeshesListed) {
        std::printf("  ... and %zu more meshes\n", listed - kMeshesListed);
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
    writeFileAtomically(out, sceneToJson(scene)); // names the mesh by its file
    std::cerr << "wrote a " << args.shape << " of " << mesh.triangleCount() << " triangles ("
              << mesh.vertices().size() << " vertices) to " << ply.string() << ", its scene to "
              << out.string() << "\n";
}

/// What `hapto scene import` takes.
struct ImportOptions {
    std::string model;
    std::string out;
    double scale = 1.0;
    std::vector<double> center{0.0, 0.0, 0.0};
    std::vector<double> rotation{1.0, 0.0, 0.0, 0.0};
    double stiffness = Material::kDefaultStiffness;
    std::vector<double> friction{0.0, 0.0};
};

/// The model as the output scene names it: relative to the scene's folder (the current folder
/// for standard output), or absolute when no relative path leads there.
std::string modelPathFromScene(const std::string& model, const std::string& out) {
    namespace fs = std::filesystem;
    const fs::path sceneDir =
        out == "-" ? fs::current_path() : fs::absolute(fs::path(out)).parent_path();
    std::error_code ec;
    const fs::path relative = fs::relative(fs::absolute(model), sceneDir, ec);
    return ec || relative.empty() ? fs::absolute(model).lexically_normal().string()
                                  : relative.generic_string();
}

/// Wraps one model file in a scene: one mesh object, id 0, bounds around it. [control]
void importModel(const ImportOptions& o) {
    checkSceneOutput(o.out);
    if (o.out != "-") {
        refuseSameFile(o.out, "-o", o.model, "the model file");
    }
    if (!(o.scale > 0.0)) {
        throw InputError("--scale: must be > 0, got " + std::to_string(o.scale));
    }
    if (!(o.stiffness > 0.0)) {
        throw InputError("--stiffness: must be > 0 N/m, got " + std::to_string(o.stiffness));
    }
    if (o.friction[1] > o.friction[0]) {
        throw InputError("--friction: the dynamic coefficient (second) must not exceed the "
                         "static one (first)");
    }
    const Quat q(o.rotation[0], o.rotation[1], o.rotation[2], o.rotation[3]);
    if (std::abs(glm::length(q) - 1.0) > 1e-3) {
        throw InputError("--rotation: expected a unit quaternion w,x,y,z (length within 1e-3 of "
                         "1), got length " +
                         std::to_string(glm::length(q)));
    }
    auto mesh = loadMeshFile(o.model, MeshSource{modelPathFromScene(o.model, o.out), o.scale});
    const Material material{o.stiffness, o.friction[0], o.friction[1]};
    std::vector<SceneObject> objects{makeMesh(0, Vec3(o.center[0], o.center[1], o.center[2]), mesh,
                                              glm::normalize(q), material)};
    const Aabb bounds = Scene::defaultBounds(objects);
    const Scene scene(bounds, std::move(objects));
    if (o.out == "-") {
        std::cout << sceneToJson(scene);
    } else {
        writeFileAtomically(o.out, sceneToJson(scene));
    }
    std::cerr << "wrote a scene with " << o.model << " (" << mesh->triangleCount() << " triangles, "
              << droppedText(mesh->droppedDegenerate(), mesh->droppedDuplicate()) << ", "
              << (mesh->closed() ? "closed" : "open") << ") to " << o.out << "\n";
}

/// What `hapto scene convert` takes.
struct ConvertOptions {
    std::string in;
    std::string out;
    std::string format; // "json", "binary" or "" (from OUT's extension)
};

/// The output format: --format, else OUT's extension (.json, .hsb). [control]
bool convertToBinary(const ConvertOptions& o) {
    if (!o.format.empty()) {
        return o.format == "binary";
    }
    const std::string ext = std::filesystem::path(o.out).extension().string();
    if (ext == ".json" || o.out == "-") {
        return false;
    }
    if (ext == ".hsb") {
        return true;
    }
    throw InputError("scene convert: cannot tell the output format from -o " + o.out +
                     " (expected a name ending in .json or .hsb); give --format json or "
                     "--format binary");
}

/// Refuses a conversion that would break the scene's references to model files: they are
/// named relative to the scene's folder and are not copied, so OUT must sit in IN's folder.
void checkModelReferences(const Scene& scene, const ConvertOptions& o) {
    namespace fs = std::filesystem;
    const fs::path inDir = fs::absolute(o.in).parent_path();
    const fs::path outDir =
        o.out == "-" ? fs::current_path() : fs::absolute(fs::path(o.out)).parent_path();
    std::error_code ec;
    if (fs::equivalent(inDir, outDir, ec)) {
        return;
    }
    for (const SceneObject& obj : scene.objects()) {
        if (obj.shape == Shape::Mesh && !obj.mesh->source().file.empty() &&
            fs::path(obj.mesh->source().file).is_relative()) {
            throw InputError("scene convert: " + o.in + ": mesh " + std::to_string(obj.id) +
                             " names its model file '" + obj.mesh->source().file +
                             "' relative to the scene's folder, and model files are referenced, "
                             "not copied: write " +
                             o.out + " into " + inDir.string());
        }
    }
}

/// JSON to binary or binary to JSON (the input told apart by its magic). [control]
void convertScene(const ConvertOptions& o) {
    const bool binary = convertToBinary(o);
    if (o.out != "-") {
        checkOutputFile(o.out, "-o");
        refuseSameFile(o.out, "-o", o.in, "the input scene");
    }
    const Scene scene = loadSceneFile(o.in);
    checkModelReferences(scene, o);
    if (o.out == "-") {
        if (binary) {
            writeBinaryScene(scene, std::cout);
        } else {
            std::cout << sceneToJson(scene);
        }
        return;
    }
    AtomicOutputFile file(o.out);
    if (binary) {
        writeBinaryScene(scene, file.stream());
    } else {
        file.stream() << sceneToJson(scene);
    }
    file.commit();
    std::cerr << "wrote " << scene.size() << " objects to " << o.out << " ("
              << (binary ? "binary" : "JSON") << ")\n";
}

/// Adds `--size`, the cubes' edge (m). [control]
void addCubeSizeOption(CLI::App* cmd, double& size) {
    cmd->add_option("--size", size, "Cube edge (m)")
        ->capture_default_str()
        ->check(finiteRange(1e-6, 1e3));
}

/// Adds `--seed`, `--workspace` and `--size`, the options every random cube generator shares
/// (RandomOptions, ClusterOptions). [control]
template <class Options> void addRandomCubeOptions(CLI::App* cmd, Options& o) {
    cmd->add_option("--seed", o.seed, "Random seed; same seed, same file")
        ->capture_default_str()
        ->check(finiteRange(0, kMaxSeed));
    cmd->add_option("--workspace", o.workspace, "Edge of the work cube (m)")
        ->capture_default_str()
        ->check(finiteRange(1e-6, 1e4));
    addCubeSizeOption(cmd, o.cubeSize);
}

/// Adds the required `-o,--output F` ('-' for standard output) and the callback that writes the
/// scene `make()` generates there, after refusing an output that must not be written. [control]
void addGeneratedSceneOutput(CLI::App* cmd, std::function<Scene()> make) {
    auto out = std::make_shared<std::string>();
    cmd->add_option("-o,--output", *out, "Output scene file ('-' for standard output)")->required();
    cmd->callback([out, make = std::move(make)] {
        checkSceneOutput(*out);
        writeScene(make(), *out);
    });
}

/// `hapto scene grid`. [control]
void addGridCommand(CLI::App* scene) {
    auto* cmd = scene->add_subcommand(
        "grid", "Experiment 1: K x K x K cubes on a regular lattice with gaps, bounds a little "
                "larger than the lattice");
    auto opt = std::make_shared<LatticeOptions>();
    cmd->add_option("--per-side", opt->perSide, "K, cubes per lattice side")
        ->required()
        ->check(finiteRange(1, 100000));
    addCubeSizeOption(cmd, opt->cubeSize);
    cmd->add_option("--gap", opt->gap, "Free space between neighbouring cubes (m)")
        ->capture_default_str()
        ->check(finiteRange(0, 1e3));
    addGeneratedSceneOutput(cmd, [opt] { return makeLatticeScene(*opt); });
    setExamples(cmd, {"hapto scene grid --per-side 10 -o grid10.json",
                      "hapto scene grid --per-side 100 --size 0.01 --gap 0.002 -o big.hsb"});
}

/// `hapto scene random`. [control]
void addRandomCommand(CLI::App* scene) {
    auto* cmd = scene->add_subcommand(
        "random", "Experiment 2: N cubes placed uniformly at random in a work cube centred on "
                  "the origin; bounds are the work cube");
    auto opt = std::make_shared<RandomOptions>();
    cmd->add_option("--count", opt->count, "Number of cubes (e.g. 200 or 1e6)")
        ->required()
        ->transform(wholeNumber(0, 4e9));
    addRandomCubeOptions(cmd, *opt);
    cmd->add_flag("--rotate", opt->rotate, "Give every cube a random orientation");
    cmd->add_option("--keep-clear", opt->keepClear,
                    "No object within this distance of the centre, where cursors start (m)")
        ->capture_default_str()
        ->check(finiteRange(0, 1e4));
    addGeneratedSceneOutput(cmd, [opt] { return makeRandomScene(*opt); });
    setExamples(cmd, {"hapto scene random --count 200 --seed 7 -o random200.json",
                      "hapto scene random --count 1e6 --rotate -o million.hsb"});
}

/// `hapto scene cluster`. [control]
void addClusterCommand(CLI::App* scene) {
    auto* cmd = scene->add_subcommand(
        "cluster", "A strongly non-uniform scene: N cubes in C Gaussian clusters (a uniform "
                   "grid does badly here)");
    auto opt = std::make_shared<ClusterOptions>();
    cmd->add_option("--count", opt->count, "Number of cubes (e.g. 1e5)")
        ->required()
        ->transform(wholeNumber(0, 4e9));
    cmd->add_option("--clusters", opt->clusters, "Number of clusters")
        ->capture_default_str()
        ->check(finiteRange(1, 1000000));
    addRandomCubeOptions(cmd, *opt);
    cmd->add_option("--spread", opt->spread, "Standard deviation of each cluster (m)")
        ->capture_default_str()
        ->check(finiteRange(0, 1e4));
    cmd->add_flag("--rotate", opt->rotate, "Give every cube a random orientation");
    addGeneratedSceneOutput(cmd, [opt] { return makeClusterScene(*opt); });
    setExamples(cmd, {"hapto scene cluster --count 1e5 --clusters 20 -o clusters.hsb"});
}

/// `hapto scene default`. [control]
void addDefaultCommand(CLI::App* scene) {
    auto* cmd = scene->add_subcommand(
        "default", "Write the embedded default scene (200 random 5 cm cubes, seed 2004, 4 cm "
                   "clear around the centre)");
    addGeneratedSceneOutput(cmd, [] { return makeDefaultScene(); });
    setExamples(cmd, {"hapto scene default -o default.json"});
}

/// `hapto scene mesh`. [control]
void addMeshCommand(CLI::App* scene) {
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
    setExamples(cmd, {"hapto scene mesh --triangles 1e5 -o sphere.json   # and sphere.ply",
                      "hapto scene mesh --shape terrain --triangles 2e6 --size 0.5 -o "
                      "terrain.json"});
    cmd->callback([args] { writeMeshScene(*args); });
}

/// `hapto scene import`. [control]
void addImportCommand(CLI::App* scene) {
    auto* cmd = scene->add_subcommand(
        "import", "Wrap a model file (OBJ, STL or PLY) in a scene: one mesh object, id 0, "
                  "which refers to the model by its path relative to the scene");
    auto opt = std::make_shared<ImportOptions>();
    cmd->add_option("model", opt->model, "The model file (.obj, .stl or .ply)")->required();
    cmd->add_option("--scale", opt->scale, "Uniform scale: the model's units times it give metres")
        ->capture_default_str()
        ->check(positiveRange(1e6));
    addNumberListOption(cmd, "--center", opt->center, 3, -1e6, 1e6,
                        "Where the model's origin goes, x,y,z (m); default 0,0,0");
    addNumberListOption(cmd, "--rotation", opt->rotation, 4, -1, 1,
                        "Orientation, a unit quaternion w,x,y,z; default 1,0,0,0");
    cmd->add_option("--stiffness", opt->stiffness, "Surface stiffness (N/m)")
        ->capture_default_str()
        ->check(positiveRange(Material::kMaxStiffness));
    addNumberListOption(cmd, "--friction", opt->friction, 2, 0, Material::kMaxFriction,
                        "Coulomb coefficients static,dynamic (dynamic <= static); "
                        "default 0,0");
    cmd->add_option("-o,--output", opt->out, "Output scene file ('-' for standard output)")
        ->required();
    setExamples(cmd, {"hapto scene import bunny.stl --scale 0.001 -o bunny.json   # mm to m",
                      "hapto scene import part.obj --center 0,0.1,0 --stiffness 500 -o "
                      "part.json"});
    cmd->callback([opt] { importModel(*opt); });
}

/// `hapto scene convert`. [control]
void addConvertCommand(CLI::App* scene) {
    auto* cmd = scene->add_subcommand(
        "convert", "Convert a scene between JSON and the binary format (for large scenes; "
                   "every --scene reads both)");
    auto opt = std::make_shared<ConvertOptions>();
    cmd->add_option("input", opt->in, "The scene to read (JSON or binary)")->required();
    cmd->add_option("-o,--output", opt->out,
                    "Output scene file: .json for JSON, .hsb for binary, or --format ('-' "
                    "for standard output)")
        ->required();
    cmd->add_option("--format", opt->format, "json or binary (default: from -o's extension)")
        ->check(CLI::IsMember({"json", "binary"}));
    setExamples(cmd, {"hapto scene convert million.json -o million.hsb",
                      "hapto scene convert million.hsb -o - --format json | head"});
    cmd->callback([opt] { convertScene(*opt); });
}

/// `hapto scene info`. [control]
void addInfoCommand(CLI::App* scene) {
    auto* cmd = scene->add_subcommand("info", "Load a scene (or the default) and describe it");
    auto path = std::make_shared<std::string>();
    cmd->add_option("--scene", *path, "Scene file (default: the embedded default scene)");
    setExamples(cmd, {"hapto scene info", "hapto scene info --scene grid10.json"});
    cmd->callback([path] {
        const auto t0 = std::chrono::steady_clock::now();
        const Scene s = loadSceneOrDefault(*path);
        const double secs =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        printInfo(s, path->empty() ? "(embedded default scene)" : *path, secs);
    });
}

} // namespace

void addSceneCommands(CLI::App& app) {
    CLI::App* scene = app.add_subcommand("scene", "Generate scene files, or describe one");
    scene->require_subcommand(1);

    addGridCommand(scene);
    addRandomCommand(scene);
    addClusterCommand(scene);
    addDefaultCommand(scene);
    addMeshCommand(scene);
    addImportCommand(scene);
    addConvertCommand(scene);
    addInfoCommand(scene);
    // Set last: a command inherits the footer its group has when it is added.
    setExamples(scene, {"hapto scene grid --per-side 10 -o grid10.json", "hapto scene info"});
}

} // namespace hapto::cli
