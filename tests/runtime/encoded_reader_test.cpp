// The encoded models' readers: the no-throw API on missing, corrupt and good files, and adaptive layers of the
// wrong storage kind refused by name.
#include "encoded_fixtures.h"

#include "prt/nothrow.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace prt_test;

TEST(NoThrow, StatusForMissingCorruptAndGoodFilesAndBadRanges) {
    fs::path dir = fs::temp_directory_path() / ("prt_nothrow_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    Bundle bundle = vertexBundle(3);
    bundle.mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    Layer transfer = layer("transfer", "vertex", "sh_transfer_rgb", {3, 1, 3}, "float32");
    transfer.data = {1, 1, 1, 2, 2, 2, 3, 3, 3};
    transfer.params = {{"order", 1}};
    bundle.layers.push_back(transfer);
    const std::string good = (dir / "good.glb").string(), bad = (dir / "bad.glb").string();
    writeBundle(good, bundle);

    Expected<RelightModel> missing = tryLoadRelightModel((dir / "absent.glb").string());
    EXPECT_EQ(missing.status().code, StatusCode::NotFound);
    EXPECT_NE(missing.status().message.find("absent.glb"), std::string::npos);

    // The same file with one byte of its binary chunk flipped: the checksum refuses it.
    std::string bytes;
    {
        std::ifstream in(good, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), {});
    }
    bytes[bytes.size() - 5] ^= 0x40;
    std::ofstream(bad, std::ios::binary) << bytes;
    Expected<RelightModel> corrupt = tryLoadRelightModel(bad);
    EXPECT_EQ(corrupt.status().code, StatusCode::Corrupt) << corrupt.status().message;
    EXPECT_NE(corrupt.status().message.find("bad.glb"), std::string::npos);
    std::ofstream(bad, std::ios::binary) << bytes.substr(0, bytes.size() / 2); // truncated
    EXPECT_EQ(tryLoadRelightModel(bad).status().code, StatusCode::Corrupt);

    Expected<RelightModel> loaded = tryLoadRelightModel(good);
    ASSERT_TRUE(loaded.ok()) << loaded.status().message;
    const float lighting[3] = {1, 2, 3};
    float radiance[9];
    EXPECT_TRUE(tryRelight(loaded.value(), lighting, 0, 3, radiance).ok());
    EXPECT_EQ(radiance[8], 9.0f);
    EXPECT_EQ(tryRelight(loaded.value(), lighting, 2, 4, radiance).code, StatusCode::InvalidInput);
    EXPECT_EQ(tryRelight(loaded.value(), nullptr, 0, 3, radiance).code, StatusCode::InvalidInput);
    int order = 0;
    EXPECT_EQ(tryReadLightingJson(good, &order).status().code, StatusCode::Corrupt);
    EXPECT_STREQ(statusName(StatusCode::Corrupt), "corrupt");
    fs::remove_all(dir);
}

// Crash classes of untrusted adaptive bundles (issue 20, layer type confusion): band scales or cluster indices of
// the other storage kind passed the shape check, and relight then read the empty storage (SIGSEGV). Every adaptive
// layer's component type is checked with its shape: each swap is refused (exit 3) naming the layer.
TEST(EncodedRelight, LayersOfTheWrongStorageKindAreRefusedNamingTheLayer) {
    auto refused = [](Bundle bundle, const std::string& layerName) {
        try {
            relightModel(std::move(bundle), "q.glb");
            ADD_FAILURE() << "accepted " << layerName << " of the wrong type";
        } catch (const Error& e) {
            EXPECT_EQ(e.exitCode(), kExitInput);
            EXPECT_NE(std::string(e.what()).find(layerName), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("expected"), std::string::npos) << e.what();
        }
    };
    auto swapStorage = [](Layer& l, const std::string& type) {
        if (type.rfind("uint", 0) == 0) {
            for (float v : l.data) l.integers.push_back(uint32_t(std::max(0.0f, v)));
            l.data.clear();
        } else {
            for (uint32_t v : l.integers) l.data.push_back(float(v));
            l.integers.clear();
        }
        l.componentType = type;
    };
    for (bool perCluster : {false, true}) {
        Quantised q = quantisedBundle(300, 4, 8, perCluster, 5);
        ASSERT_NO_THROW(relightModel(q.bundle, "q.glb"));
        for (Layer& l : q.bundle.layers) {
            Bundle bad = q.bundle;
            Layer& target = *std::find_if(bad.layers.begin(), bad.layers.end(), [&](const Layer& x) { return x.name == l.name; });
            swapStorage(target, target.componentType.rfind("uint", 0) == 0 ? "float32" : "uint32");
            refused(bad, l.name);
        }
    }
    Bundle cpca = cpcaBundle(200, 3, 2, 2, 9);
    ASSERT_NO_THROW(relightModel(cpca, "c.glb"));
    for (const Layer& l : cpca.layers) {
        Bundle bad = cpca;
        Layer& target = *std::find_if(bad.layers.begin(), bad.layers.end(), [&](const Layer& x) { return x.name == l.name; });
        swapStorage(target, target.componentType.rfind("uint", 0) == 0 ? "float32" : "uint32");
        refused(bad, l.name);
    }
}
