// Streaming bundles (bundle_stream.h): a header read describes every layer and where its bytes lie, a streamed
// write is the in-memory write byte for byte, and corrupted or changed files and lying streams are refused.
#include "bundle.h"
#include "bundle_stream.h"

#include "core.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

namespace prt {
namespace {

fs::path scratch(const std::string& name) {
    fs::path dir = fs::temp_directory_path() / ("prt_bundle_stream_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    return dir / name;
}

// A bundle with every component type, a ragged and an empty layer, two objects, and layers of over 1 MiB (so
// pieces split them) whose lengths are not multiples of 4 (so views are padded).
Bundle everyKind() {
    Bundle bundle;
    const uint32_t side = 300; // 300 x 300 grid: 90,000 vertices
    for (uint32_t y = 0; y < side; ++y)
        for (uint32_t x = 0; x < side; ++x) {
            bundle.mesh.positions.insert(bundle.mesh.positions.end(), {float(x), float(y) * 0.5f, 0.25f * float(x ^ y)});
            bundle.mesh.normals.insert(bundle.mesh.normals.end(), {0.0f, 0.0f, 1.0f});
        }
    for (uint32_t y = 0; y + 1 < side; ++y)
        for (uint32_t x = 0; x + 1 < side; ++x) {
            uint32_t v = y * side + x;
            bundle.mesh.indices.insert(bundle.mesh.indices.end(), {v, v + 1, v + side, v + 1, v + side + 1, v + side});
        }
    bundle.meshName = "grid";
    BundleObject other{"tri", "occluder", {}};
    other.mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    other.mesh.indices = {0, 1, 2};
    bundle.objects.push_back(other);
    const uint64_t vertices = bundle.mesh.vertexCount();
    auto layer = [&](std::string name, std::string type, std::vector<uint64_t> shape) {
        Layer l;
        l.name = std::move(name);
        l.domain = "vertex";
        l.semantic = "test_values";
        l.shape = std::move(shape);
        l.componentType = std::move(type);
        l.params = {{"order", 3}, {"rays", 5000000000ull}, {"note", "streamed"}};
        uint64_t count = 1;
        for (uint64_t extent : l.shape) count *= extent;
        for (uint64_t i = 0; i < count; ++i) {
            if (l.componentType == "float32") l.data.push_back(std::sin(float(i) * 0.001f) * 3.0f);
            else if (l.componentType == "float16") l.data.push_back(halfToFloat(floatToHalf(std::cos(float(i)) * 100.0f)));
            else if (l.componentType == "uint8") l.integers.push_back(uint32_t(i * 7 % 256));
            else if (l.componentType == "uint16") l.integers.push_back(uint32_t(i * 31 % 65536));
            else l.integers.push_back(uint32_t(i * 2654435761u));
        }
        return l;
    };
    bundle.layers.push_back(layer("transfer", "float32", {vertices, 9, 3}));
    bundle.layers.push_back(layer("lobes", "float16", {vertices, 3, 5}));        // odd rows of halves: padded
    bundle.layers.push_back(layer("codes", "uint8", {vertices, 3}));             // 270,000 bytes, padded by 0
    bundle.layers.push_back(layer("wide", "uint16", {vertices + 1}));
    bundle.layers.back().domain = "vertex_offsets";
    bundle.layers.push_back(layer("index", "uint32", {vertices}));
    bundle.layers.push_back(layer("empty", "float32", {0, 9, 3}));
    bundle.layers.back().domain = "grid";
    bundle.layers.push_back(layer("tri_values", "uint8", {3}));
    bundle.layers.back().object = 1;
    bundle.producer = {{"tool", "prt"}, {"stage", "test"}};
    bundle.inputs = {{"mesh", "xxh128:0123456789abcdef0123456789abcdef"}};
    bundle.convention = conventionRecord();
    return bundle;
}

// Streams that copy every layer of `header` from its file.
std::vector<LayerStream> copyOf(const BundleHeader& header) {
    std::vector<LayerStream> streams(header.bundle.layers.size());
    for (size_t i = 0; i < streams.size(); ++i) {
        streams[i].byteLength = header.extents[i].byteLength;
        streams[i].write = [&header, i](const ByteSink& sink) { streamLayerBytes(header, i, sink); };
    }
    return streams;
}

TEST(BundleStream, HeaderDescribesEveryLayerAndWhereItsBytesLie) {
    const std::string file = scratch("every.glb");
    Bundle bundle = everyKind();
    writeBundle(file, bundle);
    Bundle whole = readBundle(file);
    BundleHeader header = readBundleHeader(file);
    EXPECT_EQ(header.bundle.mesh.positions, whole.mesh.positions);
    EXPECT_EQ(header.bundle.mesh.indices, whole.mesh.indices);
    ASSERT_EQ(header.bundle.objects.size(), 1u);
    EXPECT_EQ(header.bundle.objects[0].mesh.positions, whole.objects[0].mesh.positions);
    EXPECT_EQ(header.bundle.inputs, whole.inputs);
    ASSERT_EQ(header.bundle.layers.size(), whole.layers.size());
    ASSERT_EQ(header.extents.size(), whole.layers.size());
    const std::string bytes = readFileBytes(file);
    for (size_t i = 0; i < whole.layers.size(); ++i) {
        const Layer &described = header.bundle.layers[i], &read = whole.layers[i];
        SCOPED_TRACE(read.name);
        EXPECT_EQ(described.name, read.name);
        EXPECT_EQ(described.shape, read.shape);
        EXPECT_EQ(described.componentType, read.componentType);
        EXPECT_EQ(described.params, read.params);
        EXPECT_EQ(described.object, read.object);
        EXPECT_TRUE(described.data.empty() && described.integers.empty());
        uint64_t count = read.data.empty() ? read.integers.size() : read.data.size();
        EXPECT_EQ(header.extents[i].byteLength, count * (read.componentType == "uint8" ? 1 : read.componentType == "float32" ||
                                                                   read.componentType == "uint32" ? 4 : 2));
        std::string streamed;
        streamLayerBytes(header, i, [&](const void* p, size_t n) { streamed.append(static_cast<const char*>(p), n); });
        EXPECT_EQ(streamed, bytes.substr(header.extents[i].offset, header.extents[i].byteLength)); // the file's own bytes
        if (read.componentType == "float32" || read.componentType == "float16") {
            std::vector<float> values(read.data.size());
            readLayerFloats(header, i, values.data());
            EXPECT_EQ(values, read.data); // decoded as readBundle decodes
        }
    }
    // The float32 layer's bytes are its values as they lie in memory.
    ASSERT_EQ(header.extents[0].byteLength, bundle.layers[0].data.size() * 4);
    EXPECT_EQ(std::memcmp(bytes.data() + header.extents[0].offset, bundle.layers[0].data.data(), header.extents[0].byteLength), 0);
}

TEST(BundleStream, StreamedWriteIsTheInMemoryWriteByteForByte) {
    const std::string file = scratch("memory.glb"), streamedFile = scratch("streamed.glb");
    Bundle bundle = everyKind();
    writeBundle(file, bundle);
    BundleHeader header = readBundleHeader(file);
    writeBundleStreamed(streamedFile, header.bundle, copyOf(header));
    EXPECT_EQ(readFileBytes(streamedFile), readFileBytes(file));

    // Streams and in-memory layers mixed: only some layers streamed.
    Bundle mixed = header.bundle;
    std::vector<LayerStream> streams = copyOf(header);
    for (size_t i = 1; i < mixed.layers.size(); i += 2) {
        mixed.layers[i] = bundle.layers[i];
        streams[i] = {};
    }
    writeBundleStreamed(streamedFile, mixed, streams);
    EXPECT_EQ(readFileBytes(streamedFile), readFileBytes(file));
    Bundle back = readBundle(streamedFile);
    EXPECT_EQ(back.layers[3].integers, bundle.layers[3].integers);
}

TEST(BundleStream, RefusesACorruptedOrChangedFileByName) {
    const std::string file = scratch("corrupt.glb");
    writeBundle(file, everyKind());
    BundleHeader header = readBundleHeader(file);
    const uint64_t at = header.extents[2].offset + 1000; // a byte of the uint8 layer
    std::string bytes = readFileBytes(file);
    bytes[at] ^= 0x10;
    writeBytesAtomic(file + ".bad", bytes);
    try {
        readBundleHeader(file + ".bad");
        FAIL() << "read a corrupted bundle";
    } catch (const Error& e) {
        EXPECT_EQ(e.file(), file + ".bad");
        EXPECT_EQ(e.exitCode(), kExitInput);
        EXPECT_NE(std::string(e.what()).find("checksum mismatch"), std::string::npos) << e.what();
    }
    // The same byte changed after the header was read: the copy that passes it is refused at its end.
    {
        std::fstream out(file, std::ios::in | std::ios::out | std::ios::binary);
        out.seekp(std::streamoff(at));
        out.put(bytes[at]);
    }
    try {
        streamLayerBytes(header, 2, [](const void*, size_t) {});
        FAIL() << "streamed bytes that changed";
    } catch (const Error& e) {
        EXPECT_EQ(e.file(), file);
        EXPECT_NE(std::string(e.what()).find("layer codes"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("changed since"), std::string::npos) << e.what();
    }
    streamLayerBytes(header, 1, [](const void*, size_t) {}); // the other layers are as they were
}

TEST(BundleStream, RefusesStreamsThatLieAndLeavesNoFile) {
    const std::string file = scratch("source.glb"), output = scratch("lied.glb");
    Bundle bundle = everyKind();
    writeBundle(file, bundle);
    BundleHeader header = readBundleHeader(file);
    auto expectRefused = [&](std::vector<LayerStream> streams, const std::string& problem) {
        try {
            writeBundleStreamed(output, header.bundle, streams);
            FAIL() << "wrote " << problem;
        } catch (const Error& e) {
            EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
        }
        EXPECT_FALSE(fs::exists(output));
    };
    std::vector<LayerStream> shorter = copyOf(header);
    shorter[0].write = [&](const ByteSink& sink) { sink(bundle.layers[0].data.data(), 400); };
    expectRefused(shorter, "gave 400 of its");
    std::vector<LayerStream> declared = copyOf(header);
    declared[0].byteLength -= 4;
    expectRefused(declared, "stream gives");
    std::vector<LayerStream> infinite = copyOf(header);
    const uint16_t inf = 0x7C00;
    infinite[1].write = [&](const ByteSink& sink) {
        streamLayerBytes(header, 0, [](const void*, size_t) {});
        std::vector<uint16_t> halves(header.extents[1].byteLength / 2, 0x3C00);
        halves[12345] = inf;
        sink(halves.data(), halves.size() * 2);
    };
    expectRefused(infinite, "float16 value is not finite");
}

} // namespace
} // namespace prt
