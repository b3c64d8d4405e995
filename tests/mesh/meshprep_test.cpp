// The meshprep stage end to end: prepareMesh / runMeshprep on files, good and bad.
#include "mesh.h"
#include "mesh_test_util.h"

#include "core.h"

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <set>
#include <sys/wait.h>

namespace prt::test {
namespace {

using nlohmann::json;

class Meshprep : public ScratchTest {
protected:
    MeshprepOptions optionsFor(const std::string& input) const {
        MeshprepOptions options;
        options.input = input;
        options.output = path("out.glb");
        options.report = path("report.json");
        return options;
    }

    // The stage must refuse `input` with an Error naming it and `problem`, and leave no file behind: no output,
    // no report, no temporary.
    void expectRejected(const std::string& input, const std::string& problem) {
        size_t filesBefore = fileCount();
        std::string message;
        try {
            runMeshprep(optionsFor(input));
            ADD_FAILURE() << "accepted " << input;
        } catch (const Error& e) {
            message = e.what();
            EXPECT_EQ(e.exitCode(), kExitInput) << message;
        }
        EXPECT_NE(message.find(input), std::string::npos) << message;
        EXPECT_NE(message.find(problem), std::string::npos) << "expected '" << problem << "' in: " << message;
        EXPECT_FALSE(fs::exists(path("out.glb")));
        EXPECT_FALSE(fs::exists(path("report.json")));
        EXPECT_EQ(fileCount(), filesBefore);
    }

    json readReport() const { return json::parse(read("report.json")); }
};

std::string cut(const std::string& bytes, double fraction) { return bytes.substr(0, size_t(bytes.size() * fraction)); }

// ---- good input ----

TEST_F(Meshprep, WeldsAnObjSoupIntoABundleWithNormalsAndAReport) {
    TriMesh cube = makeCube();
    std::string input = write("soup.obj", toObj(makeSoup(cube)));
    runMeshprep(optionsFor(input));

    Bundle bundle = readBundle(path("out.glb"));
    const TriMesh& mesh = bundle.mesh;
    ASSERT_EQ(mesh.vertexCount(), 8u);
    EXPECT_EQ(mesh.triangleCount(), 12u);
    ASSERT_EQ(mesh.normals.size(), 24u);
    for (size_t v = 0; v < 8; ++v)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(mesh.normals[3 * v + c], std::copysign(1 / std::sqrt(3.0f), mesh.positions[3 * v + c]), 1e-6);
    EXPECT_EQ(bundle.producer["stage"], "meshprep");
    EXPECT_EQ(bundle.inputs["mesh"], hashFile(input));

    json report = readReport();
    EXPECT_EQ(report["input"]["format"], "obj");
    EXPECT_EQ(report["input"]["hash"], hashFile(input));
    EXPECT_EQ(report["counts"],
              (json{{"vertices_in", 36}, {"faces_in", 12}, {"triangles_in", 12}, {"vertices_out", 8}, {"faces_out", 12}}));
    EXPECT_EQ(report["fixed"]["welded_vertices"], 28);
    EXPECT_EQ(report["fixed"]["normals"], "computed");
    EXPECT_EQ(report["boundary"], (json{{"edges", 0}, {"loops", 0}}));
    EXPECT_EQ(report["non_manifold_edges"], 0);
    EXPECT_DOUBLE_EQ(report["bounds"]["diagonal"].get<double>(), std::sqrt(3.0));
    EXPECT_TRUE(report["decimation"].is_null());
    // Output vertex k is soup vertex source_vertex[k]: the first appearance of each corner.
    std::vector<uint32_t> source = report["source_vertex"];
    ASSERT_EQ(source.size(), 8u);
    EXPECT_TRUE(std::is_sorted(source.begin(), source.end()));
    for (size_t k = 0; k < 8; ++k)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(mesh.positions[3 * k + c], cube.positions[3 * cube.indices[source[k]] + c]);
    EXPECT_EQ(fileCount(), 3u); // input, bundle, report
}

TEST_F(Meshprep, KeepsAuthoredNormalsUnlessAskedToRecompute) {
    std::string input = write("tilted.obj", "v 0 0 0\nv 1 0 0\nv 0 0 -1\nvn 0 0 1\nf 1//1 2//1 3//1\n");
    PreparedMesh kept = prepareMesh(optionsFor(input));
    EXPECT_EQ(kept.report["fixed"]["normals"], "kept");
    EXPECT_EQ(kept.mesh.normals, (std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1}));

    MeshprepOptions options = optionsFor(input);
    options.recomputeNormals = true;
    PreparedMesh computed = prepareMesh(options);
    EXPECT_EQ(computed.report["fixed"]["normals"], "computed");
    EXPECT_EQ(computed.mesh.normals, (std::vector<float>{0, 1, 0, 0, 1, 0, 0, 1, 0}));
    EXPECT_EQ(computed.report["boundary"], (json{{"edges", 3}, {"loops", 1}}));
}

TEST_F(Meshprep, DecimatesScalesAndMapsVerticesBackToTheFile) {
    TriMesh sphere = makeSphere(24, 48);
    std::string input = path("sphere.ply");
    writeWithOpenMesh(sphere, input, true);
    MeshprepOptions options = optionsFor(input);
    options.decimateTo = 500;
    options.scale = 2.0;
    PreparedMesh prepared = prepareMesh(options);
    const json& decimation = prepared.report["decimation"];
    EXPECT_EQ(decimation["faces_before"], sphere.triangleCount());
    EXPECT_LE(decimation["faces_after"].get<size_t>(), 500u);
    EXPECT_GE(decimation["faces_after"].get<size_t>(), 495u);
    EXPECT_EQ(prepared.mesh.triangleCount(), decimation["faces_after"].get<size_t>());
    std::vector<uint32_t> source = prepared.report["source_vertex"];
    ASSERT_EQ(source.size(), prepared.mesh.vertexCount());
    EXPECT_TRUE(std::is_sorted(source.begin(), source.end()));
    for (size_t k = 0; k < source.size(); ++k)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(prepared.mesh.positions[3 * k + c], 2.0f * sphere.positions[3 * source[k] + c]);
    EXPECT_NEAR(prepared.report["bounds"]["diagonal"].get<double>(), 4 * std::sqrt(3.0),
                0.1); // scaled; decimation may trim the extremes

    PreparedMesh again = prepareMesh(options);
    EXPECT_EQ(again.report, prepared.report);
    EXPECT_EQ(again.mesh.indices, prepared.mesh.indices);
}

TEST_F(Meshprep, StanfordBunnyBoundaryAgreesWithItsEulerCharacteristic) {
    std::string bunny = std::string(PRT_DATA_DIR) + "/bunny.ply";
    if (!fs::exists(bunny)) GTEST_SKIP() << bunny << " not fetched";
    PreparedMesh prepared = prepareMesh(optionsFor(bunny));
    const json& report = prepared.report;
    const TriMesh& mesh = prepared.mesh;
    EXPECT_EQ(report["counts"]["vertices_in"], 1839);
    EXPECT_EQ(report["counts"]["faces_in"], 3674);
    EXPECT_EQ(report["non_manifold_edges"], 0);
    EXPECT_EQ(report["source_vertex"].size(), mesh.vertexCount());

    // Counted independently: with every edge used once (boundary) or twice, 3F = 2E - B; and a connected genus-0
    // surface with L boundary loops has V - E + F = 2 - L.
    std::set<std::pair<uint32_t, uint32_t>> edges;
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        for (int k = 0; k < 3; ++k) {
            uint32_t a = mesh.indices[3 * t + k], b = mesh.indices[3 * t + (k + 1) % 3];
            edges.insert({std::min(a, b), std::max(a, b)});
        }
    long long V = mesh.vertexCount(), E = edges.size(), F = mesh.triangleCount();
    EXPECT_EQ(report["boundary"]["edges"].get<long long>(), 2 * E - 3 * F);
    EXPECT_EQ(report["boundary"]["loops"].get<long long>(), 2 - (V - E + F));
    std::cout << "bunny: " << report["counts"].dump() << " boundary " << report["boundary"].dump() << " fixed "
              << report["fixed"].dump() << "\n";
}

// ---- bad input: an Error naming the file, and nothing written ----

TEST_F(Meshprep, RejectsAMissingFile) { expectRejected(path("missing.obj"), "cannot open"); }

TEST_F(Meshprep, RejectsAnUnknownExtension) { expectRejected(write("mesh.xyz", "v 0 0 0\n"), "unknown mesh format"); }

TEST_F(Meshprep, RejectsGarbage) {
    std::string garbage(4000, '\0');
    uint32_t state = 12345;
    for (char& c : garbage) c = char((state = state * 1664525u + 1013904223u) >> 24);
    expectRejected(write("garbage.obj", garbage), "not a text file");
    expectRejected(write("garbage.off", garbage), "not a text file");
    expectRejected(write("garbage.ply", garbage), "not a PLY file");
    expectRejected(write("garbage.stl", garbage), "binary STL declares");
    expectRejected(write("garbage.glb", garbage), "");
}

TEST_F(Meshprep, RejectsTruncatedObj) {
    std::string obj = toObj(makeSphere(6, 8));
    size_t vertexLine = obj.find("v ", obj.size() / 8);
    expectRejected(write("cut_vertex.obj", obj.substr(0, obj.find(' ', vertexLine + 2) + 1)), "fewer than 3 numbers");
    size_t faceLine = obj.find("f ", obj.size() / 2);
    expectRejected(write("cut_face.obj", obj.substr(0, faceLine + 4)), "fewer than 3 corners");
}

TEST_F(Meshprep, RejectsTruncatedPly) {
    writeWithOpenMesh(makeSphere(6, 8), path("sphere.ply"), true);
    std::string binary = read("sphere.ply");
    fs::remove(path("sphere.ply"));
    expectRejected(write("cut_data.ply", cut(binary, 0.7)), "data ends before");
    expectRejected(write("cut_header.ply", binary.substr(0, binary.find("end_header") - 20)), "ends before end_header");
    writeWithOpenMesh(makeSphere(6, 8), path("ascii.ply"), false);
    std::string ascii = read("ascii.ply");
    fs::remove(path("ascii.ply"));
    expectRejected(write("cut_ascii.ply", cut(ascii, 0.9)), "data ends before");
}

TEST_F(Meshprep, RejectsTruncatedStlAndOff) {
    writeWithOpenMesh(makeSphere(6, 8), path("sphere.stl"), true);
    std::string binary = read("sphere.stl");
    writeWithOpenMesh(makeSphere(6, 8), path("ascii.stl"), false);
    std::string ascii = read("ascii.stl");
    writeWithOpenMesh(makeSphere(6, 8), path("sphere.off"), false);
    std::string off = read("sphere.off");
    for (const char* name : {"sphere.stl", "ascii.stl", "sphere.off"}) fs::remove(path(name));
    expectRejected(write("cut.stl", cut(binary, 0.5)), "truncated");
    expectRejected(write("cut_ascii.stl", cut(ascii, 0.5)), "truncated");
    expectRejected(write("cut.off", cut(off, 0.8)), "truncated");
}

TEST_F(Meshprep, RejectsTruncatedGltfAndGlb) {
    Bundle bundle;
    bundle.mesh = makeSphere(6, 8);
    writeBundle(path("sphere.glb"), bundle);
    std::string glb = read("sphere.glb");
    fs::remove(path("sphere.glb"));
    expectRejected(write("cut.glb", cut(glb, 0.6)), "truncated");
    expectRejected(write("cut.gltf", R"({"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attri)"), "");
}

TEST_F(Meshprep, RejectsNonFiniteCoordinates) {
    expectRejected(write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n"), "line 3: vertex 2: non-finite coordinate 'nan'");
    expectRejected(write("inf.off", "OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n"), "non-finite coordinate 'inf'");
    expectRejected(write("huge.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n"), "non-finite coordinate");

    // Binary PLY stores the NaN itself; validation finds it after OpenMesh has read it.
    writeWithOpenMesh(makeCube(), path("cube.ply"), true);
    std::string ply = read("cube.ply");
    fs::remove(path("cube.ply"));
    size_t data = ply.find("end_header\n") + 11;
    float nan = NAN;
    std::memcpy(&ply[data + 12 * 5 + 4], &nan, 4); // vertex 5, y
    expectRejected(write("nan.ply", ply), "vertex 5: non-finite position");

    writeWithOpenMesh(makeCube(), path("cube.stl"), true);
    std::string stl = read("cube.stl");
    fs::remove(path("cube.stl"));
    std::memcpy(&stl[84 + 50 * 3 + 12 + 4], &nan, 4); // triangle 3, first corner, y
    expectRejected(write("nan.stl", stl), "triangle 3: non-finite coordinate");
}

TEST_F(Meshprep, RejectsIndicesOutOfRange) {
    expectRejected(write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 9\n"),
                   "triangle 1: vertex index 8 out of range (3 vertices)");
    expectRejected(write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"), "OBJ indices start at 1");
    expectRejected(write("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), "triangle 0: vertex index 3 out of range");
    expectRejected(write("range.ply",
                         "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                         "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
                   "vertex index 7 out of range");
}

TEST_F(Meshprep, RejectsEmptyMeshes) {
    expectRejected(write("empty.obj", ""), "empty mesh");
    expectRejected(write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "empty mesh");
    expectRejected(write("points.ply",
                         "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                         "element face 0\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n"),
                   "empty mesh");
}

TEST_F(Meshprep, RejectsAllDegenerateMeshes) {
    expectRejected(write("line.obj", "v 0 0 0\nv 1 1 1\nv 2 2 2\nv 3 3 3\nf 1 2 3\nf 2 3 4\n"), "all 2 triangles are degenerate");
    expectRejected(write("repeats.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 1 2\nf 3 3 3\n"), "all 2 faces are degenerate");
}

TEST_F(Meshprep, RefusesAnOutputThatIsNotGlbBeforeReadingAnything) {
    MeshprepOptions options = optionsFor(write("cube.obj", toObj(makeCube())));
    options.output = path("out.obj");
    try {
        runMeshprep(options);
        ADD_FAILURE() << "accepted an .obj output";
    } catch (const Error& e) {
        EXPECT_EQ(e.exitCode(), kExitUsage);
    }
    EXPECT_EQ(fileCount(), 1u);
}

TEST_F(Meshprep, WritesNeitherFileWhenTheBundleCannotBeWritten) {
    MeshprepOptions options = optionsFor(write("cube.obj", toObj(makeCube())));
    fs::create_directory(path("out.glb")); // the bundle cannot be renamed onto a folder
    try {
        runMeshprep(options);
        ADD_FAILURE() << "wrote a bundle onto a folder";
    } catch (const Error& e) {
        EXPECT_EQ(e.exitCode(), kExitOutput) << e.what();
    }
    EXPECT_TRUE(fs::is_directory(path("out.glb")));
    EXPECT_FALSE(fs::exists(path("report.json")));
    EXPECT_EQ(fileCount(), 2u); // the input and the folder: no temporaries
}

// The real binary, when the whole project has been built: exit code 3 and no files for bad input.
TEST_F(Meshprep, BinaryExitsWithTheInputErrorCodeAndWritesNothing) {
    std::string prt = std::string(PRT_BINARY_DIR) + "/prt";
    if (!fs::exists(prt)) GTEST_SKIP() << prt << " not built";
    std::string good = write("cube.obj", toObj(makeSoup(makeCube())));
    std::string bad = write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n");
    auto run = [&](const std::string& input) {
        std::string command =
            prt + " --quiet meshprep " + input + " -o " + path("out.glb") + " --report " + path("report.json") + " 2>/dev/null";
        int status = std::system(command.c_str());
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    };
    EXPECT_EQ(run(bad), kExitInput);
    EXPECT_FALSE(fs::exists(path("out.glb")));
    EXPECT_FALSE(fs::exists(path("report.json")));
    EXPECT_EQ(run(good), kExitOk);
    EXPECT_EQ(readBundle(path("out.glb")).mesh.vertexCount(), 8u);
    EXPECT_EQ(readReport()["counts"]["vertices_out"], 8);
}

} // namespace
} // namespace prt::test
