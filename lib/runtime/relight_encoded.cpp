// Relighting straight from encoded transfer (docs/bundle.md, "Adaptive transfer"), and the vertex-blocked layout
// (blockRows) the loader puts codes and halves in: blocked u8 / u16 codes and halves of 1..8 bands are relit 8
// vertices at a time (relight_codes.cpp, relight_vector.cpp); codes left row by row (per-cluster scales) by a fused
// kernel that reads each code once, half rows by a fused kernel with the float kernel's bits; other rows (more
// bands, halves without F16C, the last half row of an odd order) are decoded a few vertices at a time into a tile
// that stays in the L1 cache and relit there by the float kernel, so memory carries only the compressed bytes;
// clustered PCA is relit in its own basis (Sloan et al. 2003).
#include "runtime.h"

#include "runtime_internal.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

namespace prt {

namespace {

// Floats per decode tile: 16 KiB, half a typical L1 data cache, so decoding and relighting share it.
constexpr size_t kTileValues = 4096;

// An IEEE binary16 value as float, exact for every finite half: exponent and mantissa moved into a float's and
// rebiased; a subnormal (or zero) half, whose exponent field is 0, is rebiased one step further and 2^-14 taken
// off, which a float subtraction does exactly (ryg's half_to_float_fast). No operand is ever a float subnormal
// (which would cost a microcode assist each) and there is no branch, so it vectorises.
inline float halfValue(uint16_t half) {
    const uint32_t magnitude = uint32_t(half & 0x7fffu) << 13;
    const uint32_t subnormal = (magnitude & 0x0f800000u) == 0 ? 1u : 0u;
    const uint32_t bits = magnitude + (112u << 23) + (subnormal << 23), offsetBits = subnormal * 0x38800000u; // 2^-14
    float value, offset;
    std::memcpy(&value, &bits, sizeof value);
    std::memcpy(&offset, &offsetBits, sizeof offset);
    value -= offset;
    uint32_t signed_;
    std::memcpy(&signed_, &value, sizeof signed_);
    signed_ |= uint32_t(half & 0x8000u) << 16;
    std::memcpy(&value, &signed_, sizeof value);
    return value;
}

// The band-scale index of vertex `first`'s band 0 (per-vertex scales), from the block table.
size_t bandStart(const RelightModel& model, size_t first) {
    const size_t block = first / kRelightBlock;
    size_t start = model.bandBlockStarts[block];
    for (size_t v = block * kRelightBlock; v < first; ++v)
        start += size_t(std::lround(std::sqrt(double(model.offsets[v + 1] - model.offsets[v]))));
    return start;
}

// Decodes vertex rows [first, last), a run of n bands each (so their codes are contiguous from row
// offsets[first]), into `tile`: value i of band l is float(int(q) - C) * sigma_l, as decodedTransfer writes it.
// `band` is the scale index of `first`'s band 0. kN = n known at compile time (0: take n) lets the compiler
// unroll the band loops; the first pass, codes to floats, is one contiguous loop over the whole tile.
template <class Code, int kN>
PRT_ALWAYS_INLINE inline void decodeBody(const RelightModel& model, const Code* codes, int n, size_t first,
                                         size_t last, size_t band, float* tile) {
    if constexpr (kN != 0) n = kN;
    constexpr int C = sizeof(Code) == 1 ? 127 : 32767;
    const size_t values = size_t(n) * n * 3, total = (last - first) * values;
    const Code* q = codes + size_t(model.offsets[first]) * 3;
    for (size_t i = 0; i < total; ++i) tile[i] = float(int(q[i]) - C);
    const bool perCluster = !model.scaleCluster.empty();
    for (size_t v = first; v < last; ++v, band += n) {
        float* out = tile + (v - first) * values;
        const float* sigma = perCluster ? model.bandScales.data() + size_t(model.scaleCluster[v]) * model.order
                                        : model.bandScales.data() + band;
        for (int l = 0; l < n; ++l) {
            const float s = sigma[l];
            for (int i = l * l * 3; i < (l + 1) * (l + 1) * 3; ++i) out[i] *= s;
        }
    }
}

// The same decode compiled twice: for the baseline and, where the processor has it, for AVX2 (wider integer to
// float conversion). Conversion and multiply round exactly either way and FMA is not enabled, so both write the
// same bits.
template <class Code, int kN>
void decodeCodesBase(const RelightModel& model, const Code* codes, int n, size_t first, size_t last, size_t band,
                     float* tile) {
    decodeBody<Code, kN>(model, codes, n, first, last, band, tile);
}
#if PRT_HAVE_AVX2_CLONE
template <class Code, int kN>
__attribute__((target("avx2"))) void decodeCodesAvx2(const RelightModel& model, const Code* codes, int n,
                                                     size_t first, size_t last, size_t band, float* tile) {
    decodeBody<Code, kN>(model, codes, n, first, last, band, tile);
}
#define PRT_DECODE(N) (processorHasAvx2() ? decodeCodesAvx2<Code, N> : decodeCodesBase<Code, N>)
#else
#define PRT_DECODE(N) decodeCodesBase<Code, N>
#endif

template <class Code>
void decodeCodes(const RelightModel& model, const Code* codes, int n, size_t first, size_t last, size_t band,
                 float* tile) {
    switch (n) {
    case 1: return PRT_DECODE(1)(model, codes, n, first, last, band, tile);
    case 2: return PRT_DECODE(2)(model, codes, n, first, last, band, tile);
    case 3: return PRT_DECODE(3)(model, codes, n, first, last, band, tile);
    case 4: return PRT_DECODE(4)(model, codes, n, first, last, band, tile);
    case 5: return PRT_DECODE(5)(model, codes, n, first, last, band, tile);
    case 6: return PRT_DECODE(6)(model, codes, n, first, last, band, tile);
    case 7: return PRT_DECODE(7)(model, codes, n, first, last, band, tile);
    case 8: return PRT_DECODE(8)(model, codes, n, first, last, band, tile);
    default: return PRT_DECODE(0)(model, codes, n, first, last, band, tile);
    }
}

} // namespace

void relightRaggedRange(const RelightModel& model, const float* lighting, size_t first, size_t last, float* out,
                        const U8Lighting* quantised) {
    if (relightBlockedCodes(model, first, last, lighting, quantised, out) ||
        relightBlockedHalves(model, first, last, lighting, out))
        return;
    const uint32_t* offsets = model.offsets.data();
    const bool coded = model.storage == TransferStorage::Uint8 || model.storage == TransferStorage::Uint16;
    size_t band = coded && model.scaleCluster.empty() ? bandStart(model, first) : 0;
    float tile[kTileValues];
    for (size_t v = first; v < last;) {
        const uint32_t count = offsets[v + 1] - offsets[v];
        size_t run = v + 1;
        while (run < last && offsets[run + 1] - offsets[run] == count) ++run;
        const int n = int(std::lround(std::sqrt(double(count))));
        if (model.storage == TransferStorage::Float32) {
            relight(model.transfer.data() + size_t(offsets[v]) * 3, run - v, int(count), lighting, out + (v - first) * 3);
            v = run;
            continue;
        }
        if (relightCodes(model, n, v, run, band, lighting, out + (v - first) * 3)) { // codes of 4..8 bands
            band += (run - v) * size_t(n);
            v = run;
            continue;
        }
        // Halves on a processor with F16C: fused (relight_vector.cpp), leaving at most the array's last row.
        const size_t fused = model.storage == TransferStorage::Float16
                                 ? relightHalves(model, v, run, int(count), lighting, out + (v - first) * 3)
                                 : 0;
        // Tiles of whole vertices: decode, then the float kernel on the tile.
        const size_t perTile = std::max<size_t>(1, kTileValues / (size_t(count) * 3));
        for (size_t t = v + fused; t < run; t += perTile) {
            const size_t tileEnd = std::min(run, t + perTile);
            if (model.storage == TransferStorage::Float16) {
                const uint16_t* halves = model.halves.data() + size_t(offsets[t]) * 3;
                for (size_t i = 0; i < (tileEnd - t) * count * 3; ++i) tile[i] = halfValue(halves[i]);
            } else if (model.storage == TransferStorage::Uint8) {
                decodeCodes(model, model.codes8.data(), n, t, tileEnd, band, tile);
            } else {
                decodeCodes(model, model.codes16.data(), n, t, tileEnd, band, tile);
            }
            band += (tileEnd - t) * size_t(n);
            relight(tile, tileEnd - t, int(count), lighting, out + (t - first) * 3);
        }
        v = run;
    }
}

std::vector<float> cpcaProjections(const RelightModel& model, const float* lighting) {
    const size_t rows = size_t(model.cpcaClusters) * (model.cpcaComponents + 1);
    std::vector<float> rgb(rows * 3), projections(rows * 4, 0.0f);
    relight(model.cpcaBasis.data(), rows, model.order * model.order, lighting, rgb.data());
    for (size_t r = 0; r < rows; ++r) std::memcpy(&projections[r * 4], &rgb[r * 3], sizeof(float) * 3);
    return projections;
}

namespace {

typedef float V4f __attribute__((vector_size(16)));
typedef float V8f __attribute__((vector_size(32)));

#include "relight_blocks.inc"

// Per vertex and channel two sums in the two halves of an 8-float vector (lanes 0..2 and 4..6; lanes 3 and 7 hold
// 0): the even one from the mean's projection over directions i = 0, 2, 4, ..., the odd one from 0 over i = 1,
// 3, 5, ..., each product w_i * p_i rounded then added in that order, then the result even + odd. Directions i and
// i + 1 lie side by side in the projections, so one 32-byte load and one multiply-add serve both halves, and the
// chain of additions per half is M / 2 long. Per channel these are the same operations in the same order as
// scalar sums (the kernel on 4-float halves in the baseline build, on 8-float vectors in the AVX2 clone), so the
// bits depend neither on the vector width nor on kM (M known at compile time, 0: take it from `components`). Every
// vertex but the last stores all 4 lanes of its result, the fourth into the next vertex's first channel, which
// that vertex then writes.
template <int kM>
PRT_ALWAYS_INLINE inline void cpcaBody(const float* __restrict projections, const uint32_t* __restrict cluster,
                                       const float* __restrict weights, size_t components, size_t count,
                                       float* __restrict out) {
    if constexpr (kM != 0) components = kM;
    const size_t M = components;
    // Software prefetch of the weights 2 KB ahead and of the cluster indices as many vertices ahead (1 M vertices,
    // M = 8, order 5: 1.1-1.25x the rate without, alternated over seven rounds; 1 and 4 KB measured no better).
    constexpr size_t kWeightsAhead = 2048 / sizeof(float), kClustersAhead = kM != 0 ? kWeightsAhead / kM : 64;
    auto load4 = [](const float* p) {
        V4f x;
        std::memcpy(&x, p, sizeof x);
        return x;
    };
    for (size_t v = 0; v < count; ++v) {
        const float* p = projections + size_t(cluster[v]) * (M + 1) * 4;
        const float* w = weights + v * M;
        // Addresses as integers: past the arrays' ends (and for M = 0, where weights may be null) they point nowhere.
        __builtin_prefetch(reinterpret_cast<const void*>(uintptr_t(w) + kWeightsAhead * sizeof(float)));
        __builtin_prefetch(reinterpret_cast<const void*>(uintptr_t(cluster + v) + kClustersAhead * sizeof(uint32_t)));
        // The mean's projection in the even half, 0 in the odd.
        V8f sum = __builtin_shufflevector(load4(p), V4f{}, 0, 1, 2, 3, 4, 5, 6, 7);
        if constexpr (kM != 0 && kM % 8 == 0) { // weights 8 at a time, each pair's spread by a fixed shuffle
            for (size_t chunk = 0; chunk < M; chunk += 8) {
                V8f w8;
                std::memcpy(&w8, w + chunk, sizeof w8);
                unrolled(std::make_index_sequence<4>{}, [&](auto qc) PRT_ALWAYS_INLINE {
                    constexpr int a = 2 * int(decltype(qc)::value), b = a + 1;
                    V8f direction;
                    std::memcpy(&direction, p + (chunk + size_t(a) + 1) * 4, sizeof direction);
                    sum += __builtin_shufflevector(w8, w8, a, a, a, a, b, b, b, b) * direction;
                });
            }
        } else {
            size_t i = 0;
            for (; i + 1 < M; i += 2) {
                V8f direction;
                std::memcpy(&direction, p + (i + 1) * 4, sizeof direction);
                const V8f pair = {w[i], w[i], w[i], w[i], w[i + 1], w[i + 1], w[i + 1], w[i + 1]};
                sum += pair * direction;
            }
            if (i < M) { // an odd M's last direction, into the even half (the odd one adds 0 * 0)
                const V8f direction = __builtin_shufflevector(load4(p + (i + 1) * 4), V4f{}, 0, 1, 2, 3, 4, 5, 6, 7);
                const V8f single = {w[i], w[i], w[i], w[i], 0.0f, 0.0f, 0.0f, 0.0f};
                sum += single * direction;
            }
        }
        const V4f result = __builtin_shufflevector(sum, sum, 0, 1, 2, 3) + __builtin_shufflevector(sum, sum, 4, 5, 6, 7);
        if (v + 1 < count) {
            std::memcpy(out + v * 3, &result, sizeof result);
        } else {
            out[v * 3] = result[0];
            out[v * 3 + 1] = result[1];
            out[v * 3 + 2] = result[2];
        }
    }
}

// Baseline and AVX2 (no FMA, so the same bits).
template <int kM>
void cpcaBase(const float* projections, const uint32_t* cluster, const float* weights, size_t components,
              size_t count, float* out) {
    cpcaBody<kM>(projections, cluster, weights, components, count, out);
}
#if PRT_HAVE_AVX2_CLONE
template <int kM>
__attribute__((target("avx2"))) void cpcaAvx2(const float* projections, const uint32_t* cluster,
                                              const float* weights, size_t components, size_t count, float* out) {
    cpcaBody<kM>(projections, cluster, weights, components, count, out);
}
#define PRT_CPCA(M) (processorHasAvx2() ? cpcaAvx2<M> : cpcaBase<M>)
#else
#define PRT_CPCA(M) cpcaBase<M>
#endif

} // namespace

void relightCpcaRange(const RelightModel& model, const float* projections, size_t first, size_t last, float* out) {
    const size_t M = size_t(model.cpcaComponents), count = last - first;
    const uint32_t* cluster = model.cpcaCluster.data() + first;
    const float* weights = model.cpcaWeights.data() + first * M;
    switch (M) {
    case 4: return PRT_CPCA(4)(projections, cluster, weights, M, count, out);
    case 8: return PRT_CPCA(8)(projections, cluster, weights, M, count, out);
    case 16: return PRT_CPCA(16)(projections, cluster, weights, M, count, out);
    default: return PRT_CPCA(0)(projections, cluster, weights, M, count, out);
    }
}

namespace {

// The band count n of vertex v of a model with offsets.
int bandsOf(const RelightModel& model, size_t v) {
    return int(std::lround(std::sqrt(double(model.offsets[v + 1] - model.offsets[v]))));
}

// Calls f(v, n, value, scale, i) for every vertex v of a model with rowsBlocked: its n bands lie in lane i of the
// block whose values (codes or halves) start at index `value` and band scales (codes) at `scale`
// (RelightModel::rowsBlocked, blockedRuns).
template <class F>
void forEachBlockedVertex(const RelightModel& model, F&& f) {
    forEachBlockRun(model, 0, model.vertexCount, [&](int bands, size_t value, size_t scale, size_t blocks,
                                                     size_t base, const uint16_t* lanes) {
        const size_t n = size_t(bands), scales = model.storage == TransferStorage::Float16 ? 0 : n;
        for (size_t k = 0; k < blocks; ++k)
            for (size_t i = 0; i < kCodeBlock; ++i) {
                size_t v = base + k * kCodeBlock + i;
                if (lanes) {
                    if (lanes[k * kCodeBlock + i] == kPaddingLane) continue;
                    v = base + lanes[k * kCodeBlock + i];
                }
                if (v < model.vertexCount) // the last block of one order is padded
                    f(v, n, value + k * 3 * n * n * kCodeBlock, scale + k * scales * kCodeBlock, i);
            }
    });
}

// The rows of a Float16 model with rowsBlocked: value j of vertex v, widened exactly, at row offsets[v] + j / 3.
// Fills rows [offsets[V]][3].
void decodeBlockedHalves(const RelightModel& model, float* rows) {
    forEachBlockedVertex(model, [&](size_t v, size_t n, size_t value, size_t, size_t i) {
        float* row = rows + size_t(model.offsets[v]) * 3;
        for (size_t j = 0; j < 3 * n * n; ++j) row[j] = halfValue(model.halves[value + blockedCodeIndex(false, j, i)]);
    });
}

// The rows of a u8 / u16 model with rowsBlocked as decodeBody writes them: value j of band l of vertex v is
// float(int(q_j) - C) * sigma_l, at row offsets[v] + j / 3. Fills rows [offsets[V]][3].
template <class Code>
void decodeBlockedCodes(const RelightModel& model, const Code* codes, float* rows) {
    constexpr int C = sizeof(Code) == 1 ? 127 : 32767;
    forEachBlockedVertex(model, [&](size_t v, size_t n, size_t code, size_t scale, size_t i) {
        float* row = rows + size_t(model.offsets[v]) * 3;
        for (size_t l = 0; l < n; ++l) {
            const float sigma = model.bandScales[scale + l * kCodeBlock + i];
            for (size_t j = l * l * 3; j < (l + 1) * (l + 1) * 3; ++j)
                row[j] = float(int(codes[code + blockedCodeIndex(sizeof(Code) == 1, j, i)]) - C) * sigma;
        }
    });
}

// Lays out the rows (codes with per-vertex scales, or halves: `padding` is C or +0) in blocks, as
// RelightModel::rowsBlocked describes: with `runs` empty, blocks of kCodeBlock consecutive vertices of one order;
// otherwise per task block, groups of kCodeBlock vertices of one band count in vertex order, where runs (8 per task
// block, then one past the last) says where each band count's groups start and `lanes` receives each group's
// vertices.
template <class Element>
void blockRowsOf(RelightModel& model, std::vector<Element>& rows, Element padding,
                 const std::vector<BlockedRun>& runs, std::vector<uint16_t>& lanes) {
    const bool u8 = model.storage == TransferStorage::Uint8, scaled = model.storage != TransferStorage::Float16;
    const size_t V = model.vertexCount;
    const BlockedSizes sizes = blockedSizes(model, runs);
    std::vector<Element> blocked(sizes.values, padding);
    std::vector<float> blockedScales(sizes.scales, 0.0f);
    if (!runs.empty()) lanes.assign(runs.back().group * kCodeBlock, kPaddingLane);
    size_t band = 0, placed[9] = {}; // placed[n]: vertices of n bands put in the current task block's groups so far
    for (size_t v = 0; v < V; ++v) {
        const size_t n = size_t(bandsOf(model, v)), values = 3 * n * n, scales = scaled ? n : 0;
        size_t value, scale, i;
        if (runs.empty()) {
            const size_t b = v / kCodeBlock;
            value = b * values * kCodeBlock, scale = b * scales * kCodeBlock, i = v % kCodeBlock;
        } else {
            const size_t t = v / kRelightBlock;
            if (v % kRelightBlock == 0) std::fill(std::begin(placed), std::end(placed), size_t(0));
            const BlockedRun& run = runs[8 * t + n - 1];
            const size_t k = placed[n] / kCodeBlock;
            i = placed[n]++ % kCodeBlock;
            value = run.value + k * values * kCodeBlock, scale = run.scale + k * scales * kCodeBlock;
            lanes[(run.group + k) * kCodeBlock + i] = uint16_t(v - t * kRelightBlock);
        }
        for (size_t j = 0; j < values; ++j)
            blocked[value + blockedCodeIndex(u8, j, i)] = rows[size_t(model.offsets[v]) * 3 + j];
        for (size_t l = 0; l < scales; ++l) blockedScales[scale + l * kCodeBlock + i] = model.bandScales[band + l];
        band += scales;
    }
    rows = std::move(blocked);
    if (scaled) model.bandScales = std::move(blockedScales);
}

// Where each task block's groups of each band count start (RelightModel::blockedRuns), for a model whose vertices
// have 1..8 bands; `scaled`: codes, with a band scale per lane and band.
std::vector<BlockedRun> blockedRunsOf(const RelightModel& model, bool scaled) {
    const size_t V = model.vertexCount, tasks = (V + kRelightBlock - 1) / kRelightBlock;
    std::vector<BlockedRun> runs(tasks * 8 + 1);
    BlockedRun at;
    for (size_t t = 0; t < tasks; ++t) {
        size_t count[9] = {};
        for (size_t v = t * kRelightBlock; v < std::min(V, (t + 1) * kRelightBlock); ++v) ++count[bandsOf(model, v)];
        for (size_t n = 1; n <= 8; ++n) {
            runs[8 * t + n - 1] = at;
            const size_t groups = (count[n] + kCodeBlock - 1) / kCodeBlock;
            at.group += groups;
            at.value += groups * 3 * n * n * kCodeBlock;
            at.scale += scaled ? groups * n * kCodeBlock : 0;
        }
    }
    runs.back() = at;
    return runs;
}

} // namespace

BlockedSizes blockedSizes(const RelightModel& model, const std::vector<BlockedRun>& runs) {
    const bool scaled = model.storage != TransferStorage::Float16;
    if (!runs.empty()) return {size_t(runs.back().value), scaled ? size_t(runs.back().scale) : 0};
    const size_t n = size_t(model.order), blocks = (size_t(model.vertexCount) + kCodeBlock - 1) / kCodeBlock;
    return {blocks * 3 * n * n * kCodeBlock, scaled ? blocks * n * kCodeBlock : 0};
}

std::vector<float> decodedTransfer(const RelightModel& model) {
    const size_t dim = size_t(model.order) * model.order * 3;
    switch (model.storage) {
    case TransferStorage::Float32: return model.transfer;
    case TransferStorage::Float16: {
        if (model.rowsBlocked) {
            std::vector<float> rows(size_t(model.offsets[model.vertexCount]) * 3);
            decodeBlockedHalves(model, rows.data());
            return rows;
        }
        std::vector<float> rows(model.halves.size());
        for (size_t i = 0; i < rows.size(); ++i) rows[i] = halfValue(model.halves[i]);
        return rows;
    }
    case TransferStorage::Uint8:
    case TransferStorage::Uint16: {
        std::vector<float> rows(size_t(model.offsets[model.vertexCount]) * 3);
        if (model.rowsBlocked) {
            if (model.storage == TransferStorage::Uint8) decodeBlockedCodes(model, model.codes8.data(), rows.data());
            else decodeBlockedCodes(model, model.codes16.data(), rows.data());
            return rows;
        }
        size_t band = 0;
        for (size_t v = 0; v < model.vertexCount; ++v) {
            const int n = bandsOf(model, v);
            float* out = rows.data() + size_t(model.offsets[v]) * 3; // decodeCodes writes vertex v at out + 0
            if (model.storage == TransferStorage::Uint8)
                decodeCodes(model, model.codes8.data(), n, v, v + 1, band, out);
            else
                decodeCodes(model, model.codes16.data(), n, v, v + 1, band, out);
            band += size_t(n);
        }
        return rows;
    }
    case TransferStorage::Cpca: {
        const size_t M = size_t(model.cpcaComponents);
        std::vector<float> rows(size_t(model.vertexCount) * dim);
        for (size_t v = 0; v < model.vertexCount; ++v) {
            const float* block = model.cpcaBasis.data() + size_t(model.cpcaCluster[v]) * (M + 1) * dim;
            for (size_t d = 0; d < dim; ++d) { // the same sums, in the same order, as lib/adapt's reconstruct
                float value = block[d];
                for (size_t i = 0; i < M; ++i) value += model.cpcaWeights[v * M + i] * block[(i + 1) * dim + d];
                rows[v * dim + d] = value;
            }
        }
        return rows;
    }
    }
    return {};
}

bool blockRows(RelightModel& model) {
    const bool coded = model.storage == TransferStorage::Uint8 || model.storage == TransferStorage::Uint16;
    const bool halves = model.storage == TransferStorage::Float16 && processorHasF16c();
    const size_t V = model.vertexCount;
    if (!(coded || halves) || model.rowsBlocked || !model.scaleCluster.empty() || model.order < 1 ||
        model.order > 8 || model.offsets.size() != V + 1 || model.offsets[0] != 0)
        return false;
    // Every vertex of 1..order bands, values and scales of the sizes the offsets describe; else left as it is.
    size_t bands = 0;
    bool ragged = false;
    for (size_t v = 0; v < V; ++v) {
        if (model.offsets[v + 1] < model.offsets[v]) return false;
        const int n = bandsOf(model, v);
        if (n < 1 || n > model.order || model.offsets[v + 1] - model.offsets[v] != uint32_t(n * n)) return false;
        ragged = ragged || n != model.order;
        bands += size_t(n);
    }
    const size_t values = model.storage == TransferStorage::Uint8    ? model.codes8.size()
                          : model.storage == TransferStorage::Uint16 ? model.codes16.size()
                                                                     : model.halves.size();
    if (values != size_t(model.offsets[V]) * 3 || (coded && model.bandScales.size() != bands)) return false;
    const std::vector<BlockedRun> runs = ragged ? blockedRunsOf(model, coded) : std::vector<BlockedRun>{};
    if (model.storage == TransferStorage::Uint8)
        blockRowsOf(model, model.codes8, uint8_t(127), runs, model.blockedLanes);
    else if (model.storage == TransferStorage::Uint16)
        blockRowsOf(model, model.codes16, uint16_t(32767), runs, model.blockedLanes);
    else
        blockRowsOf(model, model.halves, uint16_t(0), runs, model.blockedLanes);
    model.blockedRuns = runs;
    model.rowsBlocked = true;
    return true;
}

size_t relightBytes(const RelightModel& model) {
    auto bytes = [](const auto& array) { return array.size() * sizeof(array[0]); };
    if (model.rowsBlocked) // the blocked kernel reads neither offsets nor the block table
        return bytes(model.codes8) + bytes(model.codes16) + bytes(model.halves) + bytes(model.bandScales) +
               bytes(model.albedo) + bytes(model.blockedRuns) + bytes(model.blockedLanes);
    size_t total = bytes(model.offsets) + bytes(model.albedo) + bytes(model.bandBlockStarts);
    switch (model.storage) {
    case TransferStorage::Float32: return total + bytes(model.transfer);
    case TransferStorage::Float16: return total + bytes(model.halves);
    case TransferStorage::Uint8:
    case TransferStorage::Uint16:
        return total + bytes(model.codes8) + bytes(model.codes16) + bytes(model.bandScales) + bytes(model.scaleCluster);
    case TransferStorage::Cpca:
        return total + bytes(model.cpcaBasis) + bytes(model.cpcaWeights) + bytes(model.cpcaCluster);
    }
    return total;
}

} // namespace prt
