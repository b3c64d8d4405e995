#include "bundle.h"
#include "bundle_internal.h"

#include "core.h"

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <numeric>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

fs::path scratch(const std::string& name) {
    fs::path dir = fs::temp_directory_path() / ("prt_bundle_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    return dir / name;
}

// Deterministic arbitrary bit patterns: NaNs with payloads, infinities, denormals, negative zero all occur.
std::vector<float> arbitraryFloats(size_t count, uint32_t seed) {
    std::vector<float> values(count);
    uint32_t state = seed;
    for (float& value : values) {
        state = state * 1664525u + 1013904223u;
        std::memcpy(&value, &state, 4);
    }
    return values;
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

// A tetrahedron wound counter-clockwise from outside, with every per-vertex array and awkward exact values.
prt::TriMesh tetrahedron() {
    prt::TriMesh mesh;
    mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    mesh.positions[0] = -0.0f;
    mesh.positions[1] = 1e-40f; // denormal
    mesh.normals = {-0.57735f, -0.57735f, -0.57735f, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    mesh.texcoords = {0, 0, 1, 0, 0, 1, 0.1f, 0.9f};
    mesh.albedo = {0.8f, 0.1f, 0.1f, 0.1f, 0.8f, 0.1f, 0.1f, 0.1f, 0.8f, 0.5f, 0.5f, 0.5f};
    mesh.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    return mesh;
}

prt::Layer layer(std::string name, std::string domain, std::string semantic, std::vector<uint64_t> shape, uint32_t seed,
                 json params = json::object()) {
    prt::Layer layer;
    layer.name = std::move(name);
    layer.domain = std::move(domain);
    layer.semantic = std::move(semantic);
    layer.shape = std::move(shape);
    layer.params = std::move(params);
    size_t count = std::accumulate(layer.shape.begin(), layer.shape.end(), size_t(1), std::multiplies<>());
    layer.data = arbitraryFloats(count, seed);
    return layer;
}

prt::Bundle sampleBundle() {
    prt::Bundle bundle;
    bundle.mesh = tetrahedron();
    bundle.producer = {{"tool", "prt"}, {"version", "0.1.0"}, {"stage", "test"}};
    bundle.inputs = {{"mesh", "xxh128:0123456789abcdef0123456789abcdef"}, {"env", {{"path", "a.exr"}, {"order", 3}}}};
    bundle.convention = prt::conventionRecord();
    bundle.layers.push_back(layer("transfer", "vertex", "sh_transfer_rgb", {4, 9, 3}, 1,
                                  {{"order", 3}, {"mode", "interreflected"}, {"samples", 4096}, {"bounces", 2},
                                   {"seed", uint64_t(12345678901234)}, {"scale", 0.125}, {"note", "é ☃\t"},
                                   {"weight", 1.4007034301757812}}));
    bundle.layers.push_back(layer("ao", "texel", "ambient_occlusion", {8 * 4, 1}, 2, {{"width", 8}, {"height", 4}}));
    bundle.layers.push_back(layer("fiv", "occluder", "field_irradiance_sh", {2 * 4 * 4 * 4, 9, 3}, 3,
                                  {{"grid", {{"resolution", {4, 4, 4}}, {"bounds", {{-1.0, -1.0, -1.0}, {1.0, 1.0, 1.0}}}}}}));
    bundle.layers.push_back(layer("lobes", "lobe", "sg_lobe", {4 * 2, 7}, 4, {{"lobesPerVertex", 2}}));
    prt::Layer external = layer("radiance_atlas", "texel", "radiance_rgb", {16 * 16, 3}, 5,
                                {{"width", 16}, {"height", 16}, {"uri", "atlas.exr"}});
    external.data.clear();
    bundle.layers.push_back(external);
    bundle.layers.push_back(layer("empty", "lobe", "sg_lobe", {0, 7}, 6));
    return bundle;
}

void expectSameBundle(const prt::Bundle& a, const prt::Bundle& b) {
    EXPECT_TRUE(sameBits(a.mesh.positions, b.mesh.positions));
    EXPECT_TRUE(sameBits(a.mesh.normals, b.mesh.normals));
    EXPECT_TRUE(sameBits(a.mesh.texcoords, b.mesh.texcoords));
    EXPECT_TRUE(sameBits(a.mesh.albedo, b.mesh.albedo));
    EXPECT_EQ(a.mesh.indices, b.mesh.indices);
    EXPECT_EQ(a.producer, b.producer);
    EXPECT_EQ(a.inputs, b.inputs);
    EXPECT_EQ(a.convention, b.convention);
    ASSERT_EQ(a.layers.size(), b.layers.size());
    for (size_t i = 0; i < a.layers.size(); ++i) {
        SCOPED_TRACE(a.layers[i].name);
        EXPECT_EQ(a.layers[i].name, b.layers[i].name);
        EXPECT_EQ(a.layers[i].domain, b.layers[i].domain);
        EXPECT_EQ(a.layers[i].semantic, b.layers[i].semantic);
        EXPECT_EQ(a.layers[i].shape, b.layers[i].shape);
        EXPECT_EQ(a.layers[i].params, b.layers[i].params);
        EXPECT_TRUE(sameBits(a.layers[i].data, b.layers[i].data));
    }
}

// The two chunks of a GLB, split by the layout docs/bundle.md describes (independently of tinygltf).
struct Glb {
    json document;
    std::string bin;
};

uint32_t readU32(const std::string& bytes, size_t at) {
    uint32_t value;
    std::memcpy(&value, bytes.data() + at, 4);
    return value;
}

Glb splitGlb(const std::string& bytes) {
    uint32_t jsonLength = readU32(bytes, 12);
    Glb glb{json::parse(bytes.substr(20, jsonLength)), {}};
    size_t binHeader = 20 + jsonLength;
    if (binHeader < bytes.size()) glb.bin = bytes.substr(binHeader + 8, readU32(bytes, binHeader));
    return glb;
}

std::string joinGlb(const Glb& glb) {
    std::string text = glb.document.dump();
    text.resize((text.size() + 3) / 4 * 4, ' ');
    std::string bin = glb.bin;
    bin.resize((bin.size() + 3) / 4 * 4, '\0');
    auto u32 = [](size_t value) {
        uint32_t v = uint32_t(value);
        return std::string(reinterpret_cast<const char*>(&v), 4);
    };
    return "glTF" + u32(2) + u32(12 + 8 + text.size() + 8 + bin.size()) + u32(text.size()) + "JSON" + text +
           u32(bin.size()) + std::string("BIN\0", 4) + bin;
}

std::string canonical(const json& value) {
    std::string text;
    prt::detail::appendCanonicalJson(value, text);
    return text;
}

// The checksum as docs/bundle.md states it, from the file's own chunks.
std::string documentedChecksum(const Glb& glb) {
    json extension = glb.document["extensions"]["PRT_bundle"];
    extension.erase("checksum");
    size_t byteLength = glb.document["buffers"][0]["byteLength"];
    std::string hashed = glb.bin.substr(0, byteLength) + canonical(extension);
    return prt::hashBytes(hashed.data(), hashed.size());
}

std::string writeSample(const std::string& name) {
    std::string path = scratch(name).string();
    prt::writeBundle(path, sampleBundle());
    return path;
}

void expectReadError(const std::string& path, const std::string& fragment) {
    try {
        prt::readBundle(path);
        ADD_FAILURE() << "no error for " << path;
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
        EXPECT_NE(e.exitCode(), prt::kExitOk);
    }
}

// A glTF written by tinygltf, as other tools would: two nodes instance one mesh, one of them mirrored.
tinygltf::Model plainModel(bool withColor) {
    tinygltf::Model model;
    model.asset.version = "2.0";
    std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    std::vector<float> normals = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    std::vector<uint8_t> colors = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255};
    std::vector<uint16_t> indices = {0, 1, 2, 0};
    tinygltf::Buffer buffer;
    auto append = [&](const void* data, size_t size) {
        tinygltf::BufferView view;
        view.buffer = 0;
        view.byteOffset = buffer.data.size();
        view.byteLength = size;
        buffer.data.insert(buffer.data.end(), (const unsigned char*)data, (const unsigned char*)data + size);
        model.bufferViews.push_back(view);
        return int(model.bufferViews.size()) - 1;
    };
    auto accessor = [&](int view, int componentType, int type, size_t count, bool normalized) {
        tinygltf::Accessor a;
        a.bufferView = view;
        a.componentType = componentType;
        a.type = type;
        a.count = count;
        a.normalized = normalized;
        model.accessors.push_back(a);
        return int(model.accessors.size()) - 1;
    };
    tinygltf::Primitive triangles;
    triangles.mode = TINYGLTF_MODE_TRIANGLES;
    triangles.attributes["POSITION"] = accessor(append(positions.data(), 36), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 3, false);
    model.accessors.back().minValues = {0, 0, 0};
    model.accessors.back().maxValues = {1, 1, 0};
    triangles.attributes["NORMAL"] = accessor(append(normals.data(), 36), TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 3, false);
    if (withColor)
        triangles.attributes["COLOR_0"] =
            accessor(append(colors.data(), 12), TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_TYPE_VEC4, 3, true);
    triangles.indices = accessor(append(indices.data(), 8), TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, TINYGLTF_TYPE_SCALAR, 3, false);
    tinygltf::Material material;
    material.pbrMetallicRoughness.baseColorFactor = {0.5, 0.25, 1.0, 1.0};
    material.pbrMetallicRoughness.metallicFactor = 0.0; // glTF's default is 1, a metal: no diffuse albedo
    model.materials.push_back(material);
    triangles.material = 0;
    tinygltf::Primitive lines = triangles;
    lines.mode = TINYGLTF_MODE_LINE;
    tinygltf::Mesh mesh;
    mesh.primitives = {triangles, lines};
    model.meshes.push_back(mesh);
    model.buffers.push_back(buffer);
    tinygltf::Node shifted, mirrored, root;
    shifted.mesh = 0;
    shifted.translation = {10, 0, 0};
    mirrored.mesh = 0;
    mirrored.scale = {-1, 1, 1};
    root.children = {1, 2};
    root.translation = {0, 0, 5};
    model.nodes = {root, shifted, mirrored};
    tinygltf::Scene scene;
    scene.nodes = {0};
    model.scenes.push_back(scene);
    model.defaultScene = 0;
    return model;
}

void writeModel(const tinygltf::Model& model, const std::string& path, bool binary) {
    tinygltf::TinyGLTF writer;
    ASSERT_TRUE(writer.WriteGltfSceneToFile(&model, path, true, true, false, binary));
}

} // namespace

TEST(Bundle, RoundTripIsBitExact) {
    std::string path = writeSample("roundtrip.glb");
    prt::Bundle read = prt::readBundle(path);
    expectSameBundle(sampleBundle(), read);
    // 64-bit integers beyond int32 come back as doubles of the same value.
    EXPECT_EQ(read.layers[0].params["seed"].get<double>(), 12345678901234.0);
    EXPECT_TRUE(read.layers[4].data.empty());
}

TEST(Bundle, WritingIsDeterministic) {
    std::string a = writeSample("det-a.glb"), b = writeSample("det-b.glb");
    EXPECT_EQ(prt::readFileBytes(a), prt::readFileBytes(b));
}

TEST(Bundle, FindLayerByName) {
    prt::Bundle bundle = sampleBundle();
    ASSERT_NE(prt::findLayer(bundle, "fiv"), nullptr);
    EXPECT_EQ(prt::findLayer(bundle, "fiv")->domain, "occluder");
    EXPECT_EQ(prt::findLayer(bundle, "missing"), nullptr);
}

TEST(Bundle, ChecksumFollowsTheDocumentedRecipe) {
    Glb glb = splitGlb(prt::readFileBytes(writeSample("recipe.glb")));
    const json& extension = glb.document["extensions"]["PRT_bundle"];
    EXPECT_EQ(extension["version"], prt::kBundleVersion);
    EXPECT_EQ(extension["checksum"], documentedChecksum(glb));
    EXPECT_EQ(extension["checksum"].get<std::string>().rfind("xxh128:", 0), 0u);
}

TEST(Bundle, CanonicalJsonMatchesPythonJsonDumps) {
    // Expected texts are Python's json.dumps(value, sort_keys=True, separators=(",", ":"), ensure_ascii=False).
    EXPECT_EQ(canonical(json::parse(R"({"b":[1,-2,true,null],"a":{"z":"x","é":"\u0001\t\"\\/"},"B":0.5})")),
              "{\"B\":0.5,\"a\":{\"z\":\"x\",\"é\":\"\\u0001\\t\\\"\\\\/\"},\"b\":[1,-2,true,null]}");
    std::vector<std::pair<double, std::string>> numbers = {
        {0.1, "0.1"}, {1.0, "1.0"}, {-0.0, "-0.0"}, {100.0, "100.0"}, {1e15, "1000000000000000.0"}, {1e16, "1e+16"},
        {4.453736775050854e16, "4.453736775050854e+16"}, {1.4007034301757812, "1.4007034301757812"}, {1e-4, "0.0001"},
        {1e-5, "1e-05"}, {1.5e-7, "1.5e-07"}, {5e-324, "5e-324"}, {3e300, "3e+300"}, {2.0 / 3.0, "0.6666666666666666"},
        {0.025293350219726562, "0.025293350219726562"}};
    for (auto [value, text] : numbers) EXPECT_EQ(canonical(json(value)), text);
}

TEST(Bundle, StandardViewersSeeOnePlainMesh) {
    std::string path = writeSample("viewer.glb");
    tinygltf::TinyGLTF loader;
    tinygltf::Model model;
    std::string error, warning;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, path)) << error;
    EXPECT_EQ(model.extensionsUsed, std::vector<std::string>{"PRT_bundle"});
    EXPECT_TRUE(model.extensionsRequired.empty());
    ASSERT_EQ(model.scenes.size(), 1u);
    ASSERT_EQ(model.meshes.size(), 1u);
    ASSERT_EQ(model.meshes[0].primitives.size(), 1u);
    const tinygltf::Primitive& primitive = model.meshes[0].primitives[0];
    EXPECT_EQ(primitive.mode, TINYGLTF_MODE_TRIANGLES);
    for (const char* name : {"POSITION", "NORMAL", "TEXCOORD_0", "COLOR_0"}) EXPECT_EQ(primitive.attributes.count(name), 1u) << name;
    const tinygltf::Accessor& position = model.accessors[primitive.attributes.at("POSITION")];
    EXPECT_EQ(position.minValues, (std::vector<double>{-0.0, 0.0, 0.0}));
    EXPECT_EQ(position.maxValues, (std::vector<double>{1.0, 1.0, 1.0}));
    EXPECT_EQ(model.accessors[primitive.indices].componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);
    // Accessors cover the mesh only; the layer views (4 with data) are referenced from the extension alone.
    EXPECT_EQ(model.accessors.size(), 5u);
    EXPECT_EQ(model.bufferViews.size(), 5u + 4u);
    for (const tinygltf::BufferView& view : model.bufferViews) EXPECT_EQ(view.byteOffset % 4, 0u);
}

TEST(Bundle, PlainGltfReadsAsMeshWithoutLayers) {
    for (bool binary : {true, false}) {
        SCOPED_TRACE(binary ? "glb" : "gltf");
        std::string path = scratch(binary ? "plain.glb" : "plain.gltf").string();
        writeModel(plainModel(true), path, binary);
        prt::Bundle bundle = prt::readBundle(path);
        EXPECT_TRUE(bundle.layers.empty());
        EXPECT_TRUE(bundle.producer.empty());
        const prt::TriMesh& mesh = bundle.mesh;
        // Two instances of the triangle; the line primitive is skipped.
        ASSERT_EQ(mesh.vertexCount(), 6u);
        ASSERT_EQ(mesh.triangleCount(), 2u);
        std::vector<float> positions = {10, 0, 5, 11, 0, 5, 10, 1, 5, 0, 0, 5, -1, 0, 5, 0, 1, 5};
        EXPECT_EQ(mesh.positions, positions);
        // Mirroring keeps the z normal and flips the winding, so both triangles face +z.
        EXPECT_EQ(mesh.normals, (std::vector<float>{0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}));
        EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 1, 2, 3, 5, 4}));
        // COLOR_0 (normalized bytes, RGBA) times baseColorFactor (0.5, 0.25, 1).
        std::vector<float> albedo = {0.5f, 0, 0, 0, 0.25f, 0, 0, 0, 1, 0.5f, 0, 0, 0, 0.25f, 0, 0, 0, 1};
        EXPECT_EQ(mesh.albedo, albedo);
        EXPECT_TRUE(mesh.texcoords.empty());
    }
}

TEST(Bundle, BaseColorFactorAloneFillsAlbedo) {
    std::string path = scratch("factor.glb").string();
    tinygltf::Model model = plainModel(false);
    model.materials[0].pbrMetallicRoughness.metallicFactor = 0.0; // glTF's default is 1: a metal has no diffuse albedo
    writeModel(model, path, true);
    prt::TriMesh mesh = prt::readBundle(path).mesh;
    ASSERT_EQ(mesh.albedo.size(), 18u);
    for (size_t v = 0; v < 6; ++v) EXPECT_EQ(std::vector<float>(mesh.albedo.begin() + 3 * v, mesh.albedo.begin() + 3 * v + 3),
                                             (std::vector<float>{0.5f, 0.25f, 1.0f}));
    tinygltf::Model white = plainModel(false);
    white.materials[0].pbrMetallicRoughness.baseColorFactor = {1, 1, 1, 1};
    white.materials[0].pbrMetallicRoughness.metallicFactor = 0.0;
    writeModel(white, path, true);
    EXPECT_TRUE(prt::readBundle(path).mesh.albedo.empty());
}

TEST(Bundle, AccessorPastItsBufferIsRefused) {
    std::string path = scratch("overrun.glb").string();
    tinygltf::Model model = plainModel(true);
    model.accessors[0].count = 1000;
    writeModel(model, path, true);
    expectReadError(path, "past the end");
    model = plainModel(true);
    model.bufferViews[0].byteLength = 1 << 20;
    writeModel(model, path, true);
    EXPECT_THROW(prt::readBundle(path), prt::Error);
}

TEST(Bundle, OutOfRangeIndicesPassToValidation) {
    std::string path = scratch("bad-index.glb").string();
    tinygltf::Model model = plainModel(true);
    model.nodes[0].children = {1};
    std::vector<unsigned char>& data = model.buffers[0].data;
    uint16_t huge = 7;
    std::memcpy(data.data() + model.bufferViews[model.accessors[model.meshes[0].primitives[0].indices].bufferView].byteOffset + 2, &huge, 2);
    writeModel(model, path, true);
    prt::TriMesh mesh = prt::readBundle(path).mesh;
    EXPECT_EQ(mesh.indices, (std::vector<uint32_t>{0, 0xFFFFFFFFu, 2}));
}

TEST(Bundle, UnsupportedVersionIsRefused) {
    std::string path = writeSample("version.glb");
    Glb glb = splitGlb(prt::readFileBytes(path));
    glb.document["extensions"]["PRT_bundle"]["version"] = 4;
    prt::writeBytesAtomic(path, joinGlb(glb));
    expectReadError(path, "version 4 is not supported; this build reads versions 1 to 3");
}

TEST(Bundle, TruncatedFileIsRefused) {
    std::string good = prt::readFileBytes(writeSample("whole.glb"));
    std::string path = scratch("truncated.glb").string();
    for (size_t length : {size_t(0), size_t(3), size_t(12), size_t(19), size_t(20), size_t(64), good.size() / 3, good.size() / 2,
                          good.size() - 12, good.size() - 4, good.size() - 1}) {
        SCOPED_TRACE(length);
        prt::writeBytesAtomic(path, good.substr(0, length));
        expectReadError(path, length >= 12 ? "truncated: the header declares" : "");
    }
}

TEST(Bundle, TamperedBinaryIsRefused) {
    std::string good = prt::readFileBytes(writeSample("binary.glb"));
    size_t binStart = 20 + readU32(good, 12) + 8;
    std::string path = scratch("tampered-binary.glb").string();
    for (size_t at : {binStart, binStart + 7, (binStart + good.size()) / 2, good.size() - 1}) {
        SCOPED_TRACE(at);
        std::string bytes = good;
        bytes[at] = char(bytes[at] ^ 0x10);
        prt::writeBytesAtomic(path, bytes);
        expectReadError(path, "checksum mismatch: the bundle is truncated or was modified");
    }
}

TEST(Bundle, TamperedExtensionIsRefused) {
    std::string good = prt::readFileBytes(writeSample("extension.glb"));
    std::string path = scratch("tampered-extension.glb").string();
    // Same-length edits keep the GLB layout valid, so only the checksum can tell.
    for (auto [from, to] : {std::pair{"sh_transfer_rgb", "sh_transfer_rgc"}, std::pair{"\"samples\":4096", "\"samples\":4095"},
                            std::pair{"\"stage\":\"test\"", "\"stage\":\"tost\""}}) {
        SCOPED_TRACE(from);
        std::string bytes = good;
        size_t at = bytes.find(from);
        ASSERT_NE(at, std::string::npos);
        bytes.replace(at, std::strlen(from), to);
        prt::writeBytesAtomic(path, bytes);
        expectReadError(path, "checksum mismatch");
    }
}

TEST(Bundle, InconsistentLayerIsRefusedEvenWithValidChecksum) {
    std::string path = writeSample("inconsistent.glb");
    Glb good = splitGlb(prt::readFileBytes(path));
    for (auto [edit, fragment] : {std::pair{0, "rows but the mesh has 4 vertices"}, std::pair{1, "shape needs"}}) {
        Glb glb = good;
        json& record = glb.document["extensions"]["PRT_bundle"]["layers"][edit == 0 ? 0 : 1];
        record["shape"][0] = record["shape"][0].get<int>() + 1;
        glb.document["extensions"]["PRT_bundle"]["checksum"] = documentedChecksum(glb);
        prt::writeBytesAtomic(path, joinGlb(glb));
        expectReadError(path, fragment);
    }
}

TEST(Bundle, MissingOrForeignFileIsRefused) {
    expectReadError(scratch("does-not-exist.glb").string(), "");
    std::string text = scratch("notes.gltf").string();
    prt::writeBytesAtomic(text, "these are not the droids");
    expectReadError(text, "");
    prt::writeBytesAtomic(text, "{}");
    expectReadError(text, "");
    std::string glbMagic = scratch("magic.glb").string();
    prt::writeBytesAtomic(glbMagic, std::string("glTF\2\0\0\0", 8) + std::string(40, '\0'));
    expectReadError(glbMagic, "");
}

TEST(Bundle, FailedWriteLeavesNoFile) {
    fs::path missingFolder = scratch("no-such-folder") / "out.glb";
    fs::remove_all(missingFolder.parent_path());
    try {
        prt::writeBundle(missingFolder.string(), sampleBundle());
        ADD_FAILURE() << "no error";
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.exitCode(), prt::kExitOutput);
    }
    EXPECT_FALSE(fs::exists(missingFolder.parent_path()));

    // A refused bundle leaves an existing file untouched and no temporary file behind.
    std::string path = writeSample("keep.glb");
    std::string before = prt::readFileBytes(path);
    prt::Bundle bad = sampleBundle();
    bad.layers[0].shape[0] = 5;
    bad.layers[0].data.resize(5 * 9 * 3);
    EXPECT_THROW(prt::writeBundle(path, bad), prt::Error);
    prt::Bundle nan = sampleBundle();
    nan.layers[0].params["scale"] = std::nan("");
    EXPECT_THROW(prt::writeBundle(path, nan), prt::Error);
    EXPECT_EQ(prt::readFileBytes(path), before);
    for (const auto& entry : fs::directory_iterator(fs::path(path).parent_path()))
        EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST(Bundle, JsonIsStoredAsGltfStoresIt) {
    prt::Bundle bundle = sampleBundle();
    bundle.layers[0].params["unset"] = nullptr;
    bundle.layers[0].params["none"] = json::array();
    bundle.producer["empty"] = json::object();
    std::string path = scratch("json.glb").string();
    prt::writeBundle(path, bundle);
    prt::Bundle read = prt::readBundle(path);
    expectSameBundle(sampleBundle(), read);

    bundle.layers[0].params["views"] = {json::array(), 1};
    EXPECT_THROW(prt::writeBundle(path, bundle), prt::Error);
}
