// What an engine gets wrong when it embeds the runtime (found by a session that embedded it): an empty range with
// no lighting, a model moved from or with arrays resized after loading, relightAdaptive outside its range or on a
// clustered-PCA model, counts out of range. Each is an Error (a status from prt/nothrow.h), never a read past an
// array; each test crashed, read out of bounds under AddressSanitizer, or returned Ok before its fix.
#include "encoded_fixtures.h"

#include "prt/nothrow.h"

#include <gtest/gtest.h>

#include <utility>

namespace prt_test {
namespace {

// Blocked u8 codes of graded orders, clustered PCA, halves and float rows, all of 4,099 vertices at order 4.
std::vector<RelightModel> everyStorage() {
    std::vector<RelightModel> models;
    models.push_back(relightModel(quantisedBundle(4099, 4, 8, false, 3).bundle, "u8.glb"));
    models.push_back(relightModel(quantisedBundle(4099, 4, 16, true, 4).bundle, "u16-clusters.glb"));
    models.push_back(relightModel(cpcaBundle(4099, 4, 5, 3, 5), "cpca.glb"));
    RelightModel rows;
    rows.vertexCount = 4099;
    rows.order = 4;
    rows.transfer = decodedTransfer(models[0]);
    rows.transfer.resize(size_t(4099) * 16 * 3, 0.5f);
    models.push_back(rows);
    return models;
}

TEST(RuntimeMisuse, AnEmptyRangeReadsNoLightingWhateverTheStorage) {
    for (const RelightModel& model : everyStorage()) {
        EXPECT_NO_THROW(relight(model, nullptr, 7, 7, nullptr)) << int(model.storage);
        EXPECT_TRUE(tryRelight(model, nullptr, 4099, 4099, nullptr)) << int(model.storage);
    }
}

TEST(RuntimeMisuse, AModelMovedFromOrWithResizedArraysIsRefusedNotReadPast) {
    const std::vector<float> lighting = randomLighting(4, 1);
    for (RelightModel& model : everyStorage()) {
        std::vector<float> radiance(size_t(model.vertexCount) * 3);
        RelightModel albedoTooShort = model;
        albedoTooShort.albedo.assign(3, 0.5f);
        const RelightModel moved = std::move(model); // vertexCount and order survive the move; the arrays do not
        for (const RelightModel* broken : {&model, &albedoTooShort}) {
            const Status status = tryRelight(*broken, lighting.data(), 0, broken->vertexCount, radiance.data());
            EXPECT_EQ(status.code, StatusCode::InvalidInput) << int(moved.storage) << ": " << status.message;
            EXPECT_NE(status.message.find("the model's"), std::string::npos) << status.message;
        }
        EXPECT_TRUE(tryRelight(moved, lighting.data(), 0, moved.vertexCount, radiance.data()));
    }
    RelightModel transferTooShort = everyStorage()[3];
    transferTooShort.transfer.resize(transferTooShort.transfer.size() - 1);
    std::vector<float> radiance(size_t(4099) * 3);
    try {
        relight(transferTooShort, lighting.data(), 0, 4099, radiance.data());
        ADD_FAILURE() << "a transfer array one value short was relit";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("transfer holds 196751 values where its counts and layout say 196752"),
                  std::string::npos) << e.what();
    }
}

TEST(RuntimeMisuse, RelightAdaptiveChecksItsRangeAndItsModel) {
    const std::vector<RelightModel> models = everyStorage();
    const std::vector<float> lighting = randomLighting(4, 2);
    std::vector<float> radiance(size_t(4100) * 3);
    EXPECT_THROW(relightAdaptive(models[0], lighting.data(), 0, 4100, radiance.data()), Error); // past the end
    EXPECT_THROW(relightAdaptive(models[0], lighting.data(), 9, 3, radiance.data()), Error);    // begin > end
    EXPECT_THROW(relightAdaptive(models[2], lighting.data(), 0, 10, radiance.data()), Error);   // clustered PCA
    EXPECT_THROW(relightAdaptive(models[3], lighting.data(), 0, 10, radiance.data()), Error);   // no offsets
    EXPECT_NO_THROW(relightAdaptive(models[0], nullptr, 5, 5, nullptr));
    // Within its range it still gives relight()'s bits.
    std::vector<float> whole(size_t(4099) * 3);
    relight(models[1], lighting.data(), 0, 4099, whole.data());
    relightAdaptive(models[1], lighting.data(), 4000, 4099, radiance.data());
    EXPECT_EQ(std::memcmp(radiance.data(), whole.data() + 4000 * 3, 99 * 3 * sizeof(float)), 0);
}

TEST(RuntimeMisuse, CountsOutsideTheirRangeAreErrors) {
    const std::vector<float> lighting = randomLighting(3, 3);
    EXPECT_THROW(fitLighting(lighting.data(), 9, -4), Error);
    EXPECT_THROW(fitLighting(lighting.data(), -1, 9), Error);
    EXPECT_EQ(fitLighting(lighting.data(), 9, 4).size(), 12u);
    float transfer[3] = {1, 2, 3}, radiance[3] = {};
    EXPECT_THROW(relight(transfer, 1, 0, lighting.data(), radiance), Error);
    EXPECT_THROW(relight(transfer, 1, -3, lighting.data(), radiance), Error);
    RelightModel noOrder;
    EXPECT_THROW(relight(noOrder, lighting.data(), 0, 0, radiance), Error);
}

} // namespace
} // namespace prt_test
