// The glossy runtime's environment: the box-filtered chain that integrateLobe sums exactly, and the stack of maps
// convolved with normalised spherical Gaussians that lookupLobe reads in O(1) (docs/glossy.md, "Runtime").
// Needs only the standard library and lib/core.
#include "runtime.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace prt {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kSupportWidths = 5.5; // texels within 5.5 / sqrt(lambda) of the mean: exp(-15) of the peak beyond

// The level integrateLobe sums a lobe of this sharpness over: the coarsest whose texel spacing is at most a
// quarter of the lobe's width, the finest when none is.
size_t sumLevel(const PrefilteredEnvironment& env, double sharpness) {
    const double spread = 1.0 / std::sqrt(sharpness);
    size_t chosen = 0;
    for (size_t l = 0; l < env.levels.size(); ++l)
        if (2.0 * kPi / env.levels[l].width <= spread / 4.0) chosen = l;
    return chosen;
}

// The rows of `level` within `radius` of polar angle theta, and per row the number of columns (centred on the
// mean's column) that cover the cap there; columns 0 for a row the cap misses. Shared by integrateLobe and the
// stack so that both sum the same texels.
struct CapRow {
    int y, columns;
};
void capRows(const PrefilteredEnvironment::Level& level, double theta, double radius, std::vector<CapRow>& rows) {
    rows.clear();
    const double cosRadius = std::cos(radius);
    int rowBegin = std::max(0, int(std::floor((theta - radius) / kPi * level.height)));
    int rowEnd = std::min(level.height, int(std::ceil((theta + radius) / kPi * level.height)));
    for (int y = rowBegin; y < rowEnd; ++y) {
        double t = kPi * (y + 0.5) / level.height, st = std::sin(t), ct = std::cos(t);
        // Azimuths within the cap on this row: cos(radius) <= ct cos(theta) + st sin(theta) cos(dphi).
        double denominator = st * std::sin(theta);
        double halfWidth = kPi;
        if (denominator > 1e-12) {
            double c = (cosRadius - ct * std::cos(theta)) / denominator;
            if (c > 1.0) continue;
            if (c > -1.0) halfWidth = std::acos(c) + 2.0 * kPi / level.width;
        }
        int columns = std::min(level.width, int(std::ceil(2.0 * halfWidth / (2.0 * kPi) * level.width)) + 1);
        rows.push_back({y, columns});
    }
}

// Unit mu turned into the stored map's frame: R^T mu.
void mapDirection(const PrefilteredEnvironment& env, const float* mu, double out[3]) {
    const double* R = env.rotation;
    for (int i = 0; i < 3; ++i) out[i] = R[0 * 3 + i] * mu[0] + R[1 * 3 + i] * mu[1] + R[2 * 3 + i] * mu[2];
}

bool isIdentity(const double R[9]) {
    for (int i = 0; i < 9; ++i)
        if (R[i] != (i % 4 == 0 ? 1.0 : 0.0)) return false;
    return true;
}

// Integral of exp(lambda (mu . w - 1)) over the sphere.
double kernelIntegral(double sharpness) { return 2.0 * kPi / sharpness * -std::expm1(-2.0 * sharpness); }

double stackSharpness(int k, int levelsPerOctave) { return kStackSharpnessMin * std::exp2(double(k) / levelsPerOctave); }

// One row of a stack level: out [width][3] of the kernel-weighted mean radiance at the row's texel centres, from
// `padded` (the input level's channels planar, each row three periods long: [3][height][3 width]).
void stackRow(const PrefilteredEnvironment& env, const PrefilteredEnvironment::SharpnessLevel& target, size_t input,
              const std::vector<float>& padded, int row, float* out) {
    const PrefilteredEnvironment::Level& level = env.levels[input];
    const int width = target.width, inWidth = level.width, m = inWidth / width;
    const double sharpness = target.sharpness, spread = 1.0 / std::sqrt(sharpness);
    const double radius = std::min(kPi, kSupportWidths * spread);
    const double theta = kPi * (row + 0.5) / target.height, st0 = std::sin(theta), ct0 = std::cos(theta);
    std::vector<CapRow> rows;
    capRows(level, theta, radius, rows);
    // integrateLobe centres its columns on floor((phi + pi) / (2 pi) inWidth) = m x + m / 2 for texel x's centre.
    const int offset = m / 2;
    std::vector<double> sum(size_t(width) * 3, 0.0);
    std::vector<float> rowSum(size_t(width) * 3), kernel;
    double weight = 0.0;
    const size_t plane = size_t(level.height) * 3 * inWidth;
    for (const CapRow& r : rows) {
        double t = kPi * (r.y + 0.5) / level.height, st = std::sin(t), ct = std::cos(t);
        const int first = offset - r.columns / 2;
        kernel.resize(size_t(r.columns));
        double kernelSum = 0.0;
        for (int i = 0; i < r.columns; ++i) {
            // Texel m x + first + i against the centre of texel x: the same azimuth difference for every x.
            double dphi = 2.0 * kPi * (first + i + 0.5 - 0.5 * m) / inWidth;
            double e = std::exp(sharpness * (ct * ct0 + st * st0 * std::cos(dphi) - 1.0));
            kernel[size_t(i)] = float(e);
            kernelSum += double(float(e));
        }
        const double solidAngle = level.solidAngle[size_t(r.y)];
        weight += kernelSum * solidAngle;
        for (int c = 0; c < 3; ++c) {
            float* acc = &rowSum[size_t(c) * width];
            std::fill(acc, acc + width, 0.0f);
            const float* source = &padded[size_t(c) * plane + size_t(r.y) * 3 * inWidth + inWidth + first];
            for (int i = 0; i < r.columns; ++i) {
                const float e = kernel[size_t(i)];
                const float* s = source + i;
                if (m == 1)
                    for (int x = 0; x < width; ++x) acc[x] += e * s[x];
                else
                    for (int x = 0; x < width; ++x) acc[x] += e * s[size_t(x) * m];
            }
            for (int x = 0; x < width; ++x) sum[size_t(x) * 3 + c] += solidAngle * acc[x];
        }
    }
    for (size_t i = 0; i < sum.size(); ++i) out[i] = weight > 0.0 ? float(sum[i] / weight) : 0.0f;
}

struct StackJob {
    PrefilteredEnvironment* env;
    std::vector<size_t> input;                // per stack level: its input box level
    std::vector<std::vector<float>> padded;   // per box level: planar, three periods per row (empty when unused)
    std::vector<size_t> rowStart;             // per stack level: its first task
};

void stackTask(void* data, size_t index) {
    StackJob& job = *static_cast<StackJob*>(data);
    size_t l = size_t(std::upper_bound(job.rowStart.begin(), job.rowStart.end(), index) - job.rowStart.begin()) - 1;
    PrefilteredEnvironment::SharpnessLevel& target = job.env->sharpnessLevels[l];
    int row = int(index - job.rowStart[l]);
    stackRow(*job.env, target, job.input[l], job.padded[job.input[l]], row,
             &target.rgb[size_t(row) * target.width * 3]);
}

// Bilinear radiance of a stack level at the map direction w (unit): texel centres at ((x + 0.5) / W, (y + 0.5) / H)
// of (phi, theta); across a pole the row beyond is the edge row half a turn round, across the seam the columns wrap.
void bilinear(const PrefilteredEnvironment::SharpnessLevel& level, const double w[3], float out[3]) {
    const double theta = std::acos(std::clamp(w[1], -1.0, 1.0)), phi = std::atan2(w[0], -w[2]);
    const double u = (phi + kPi) / (2.0 * kPi) * level.width - 0.5, v = theta / kPi * level.height - 0.5;
    const double x0 = std::floor(u), y0 = std::floor(v);
    const float fx = float(u - x0), fy = float(v - y0);
    auto texel = [&](int y, int x) {
        if (y < 0) y = -1 - y, x += level.width / 2;
        if (y >= level.height) y = 2 * level.height - 1 - y, x += level.width / 2;
        x %= level.width;
        if (x < 0) x += level.width;
        return &level.rgb[(size_t(y) * level.width + x) * 3];
    };
    const int xi = int(x0), yi = int(y0);
    const float *a = texel(yi, xi), *b = texel(yi, xi + 1), *c = texel(yi + 1, xi), *d = texel(yi + 1, xi + 1);
    for (int i = 0; i < 3; ++i)
        out[i] = (1.0f - fy) * ((1.0f - fx) * a[i] + fx * b[i]) + fy * ((1.0f - fx) * c[i] + fx * d[i]);
}

} // namespace

PrefilteredEnvironment prefilterEnvironment(const float* rgb, int width, int height) {
    return prefilterEnvironment(rgb, width, height, PrefilterOptions{});
}

PrefilteredEnvironment prefilterEnvironment(const float* rgb, int width, int height, const PrefilterOptions& options) {
    if (width < 2 || height < 1 || width != 2 * height)
        throw Error("", "environment", "the glossy runtime needs a 2:1 equirectangular map");
    if (options.levelsPerOctave < 1 || options.levelsPerOctave > 8 || options.texelsPerWidth < 1 ||
        options.texelsPerWidth > 8 || !std::isfinite(options.sharpnessMin) || !std::isfinite(options.sharpnessMax))
        throw Error("", "environment", "prefilter options out of range");
    PrefilteredEnvironment env;
    PrefilteredEnvironment::Level level;
    level.width = width, level.height = height;
    level.rgb.assign(rgb, rgb + size_t(width) * height * 3);
    for (;;) {
        level.solidAngle.resize(level.height);
        for (int y = 0; y < level.height; ++y)
            level.solidAngle[y] = float(2.0 * kPi / level.width *
                                        (std::cos(kPi * y / level.height) - std::cos(kPi * (y + 1) / level.height)));
        env.levels.push_back(level);
        if (level.height % 2 || level.height < 4) break;
        const PrefilteredEnvironment::Level& fine = env.levels.back();
        PrefilteredEnvironment::Level coarse;
        coarse.width = fine.width / 2, coarse.height = fine.height / 2;
        coarse.rgb.assign(size_t(coarse.width) * coarse.height * 3, 0.0f);
        for (int y = 0; y < coarse.height; ++y)
            for (int x = 0; x < coarse.width; ++x)
                for (int c = 0; c < 3; ++c) {
                    // Solid-angle weighted: the two fine rows differ in texel size.
                    double sum = 0.0, weight = 0.0;
                    for (int dy = 0; dy < 2; ++dy)
                        for (int dx = 0; dx < 2; ++dx) {
                            double w = fine.solidAngle[2 * y + dy];
                            sum += w * fine.rgb[((size_t(2 * y + dy) * fine.width) + 2 * x + dx) * 3 + c];
                            weight += w;
                        }
                    coarse.rgb[(size_t(y) * coarse.width + x) * 3 + c] = float(sum / weight);
                }
        level = std::move(coarse);
    }

    // The stack: grid indices whose interval [lambda_k, lambda_k+1] touches the requested range.
    env.levelsPerOctave = options.levelsPerOctave;
    const int perOctave = options.levelsPerOctave;
    const int last = int(std::ceil(std::log2(kStackSharpnessMax / kStackSharpnessMin) * perOctave - 1e-9));
    const double low = std::max(options.sharpnessMin, kStackSharpnessMin);
    const double high = std::min(options.sharpnessMax, kStackSharpnessMax);
    if (!(low <= high)) return env;
    int kBegin = std::clamp(int(std::floor(std::log2(low / kStackSharpnessMin) * perOctave + 1e-9)), 0, last);
    int kEnd = std::clamp(int(std::ceil(std::log2(high / kStackSharpnessMin) * perOctave - 1e-9)), 0, last);
    if (kEnd == kBegin) kEnd = std::min(last, kBegin + 1), kBegin = kEnd - 1;
    env.firstSharpnessIndex = kBegin;
    StackJob job;
    job.env = &env;
    job.padded.resize(env.levels.size());
    size_t tasks = 0;
    for (int k = kBegin; k <= kEnd; ++k) {
        PrefilteredEnvironment::SharpnessLevel target;
        target.sharpness = stackSharpness(k, perOctave);
        const double spacing = 1.0 / (options.texelsPerWidth * std::sqrt(target.sharpness));
        size_t input = sumLevel(env, target.sharpness), output = input;
        // The coarsest level at least as coarse as the input whose spacing is still within the target spacing.
        for (size_t l = input; l < env.levels.size(); ++l)
            if (2.0 * kPi / env.levels[l].width <= spacing) output = l;
        target.width = env.levels[output].width, target.height = env.levels[output].height;
        target.rgb.assign(size_t(target.width) * target.height * 3, 0.0f);
        env.sharpnessLevels.push_back(std::move(target));
        job.input.push_back(input);
        job.rowStart.push_back(tasks);
        tasks += size_t(env.sharpnessLevels.back().height);
    }
    for (size_t input : job.input) {
        std::vector<float>& padded = job.padded[input];
        if (!padded.empty()) continue;
        const PrefilteredEnvironment::Level& from = env.levels[input];
        const size_t w = size_t(from.width), plane = size_t(from.height) * 3 * w;
        padded.resize(3 * plane);
        for (int c = 0; c < 3; ++c)
            for (int y = 0; y < from.height; ++y)
                for (size_t x = 0; x < 3 * w; ++x)
                    padded[c * plane + size_t(y) * 3 * w + x] = from.rgb[(size_t(y) * w + x % w) * 3 + c];
    }
    runTasks(options.jobs ? *options.jobs : JobSystem{}, tasks, stackTask, &job);
    return env;
}

void integrateLobe(const PrefilteredEnvironment& env, const float lobe[5], float radiance[3]) {
    radiance[0] = radiance[1] = radiance[2] = 0.0f;
    if (!(lobe[0] > 0.0f)) return;
    const double sharpness = lobe[4], spread = 1.0 / std::sqrt(sharpness);
    const PrefilteredEnvironment::Level& level = env.levels[sumLevel(env, sharpness)];
    const double radius = std::min(kPi, kSupportWidths * spread);
    double mu[3] = {lobe[1], lobe[2], lobe[3]};
    if (!isIdentity(env.rotation)) mapDirection(env, lobe + 1, mu);
    const double theta = std::acos(std::clamp(mu[1], -1.0, 1.0)), phi = std::atan2(mu[0], -mu[2]);
    std::vector<CapRow> rows;
    rows.reserve(64);
    capRows(level, theta, radius, rows);
    int center = int(std::floor((phi + kPi) / (2.0 * kPi) * level.width));
    double sum[3] = {0, 0, 0};
    for (const CapRow& r : rows) {
        double t = kPi * (r.y + 0.5) / level.height, st = std::sin(t), ct = std::cos(t);
        double rowSum[3] = {0, 0, 0};
        for (int i = 0; i < r.columns; ++i) {
            int x = ((center - r.columns / 2 + i) % level.width + level.width) % level.width;
            double p = 2.0 * kPi * (x + 0.5) / level.width - kPi;
            double w[3] = {st * std::sin(p), ct, -st * std::cos(p)};
            double e = std::exp(sharpness * (mu[0] * w[0] + mu[1] * w[1] + mu[2] * w[2] - 1.0));
            const float* L = &level.rgb[(size_t(r.y) * level.width + x) * 3];
            for (int c = 0; c < 3; ++c) rowSum[c] += e * L[c];
        }
        for (int c = 0; c < 3; ++c) sum[c] += rowSum[c] * level.solidAngle[r.y];
    }
    for (int c = 0; c < 3; ++c) radiance[c] = float(lobe[0] * sum[c]);
}

void lookupLobe(const PrefilteredEnvironment& env, const float lobe[5], float radiance[3]) {
    const std::vector<PrefilteredEnvironment::SharpnessLevel>& stack = env.sharpnessLevels;
    const double sharpness = lobe[4];
    if (stack.size() < 2 || !(sharpness >= stack.front().sharpness) || !(sharpness <= stack.back().sharpness)) {
        integrateLobe(env, lobe, radiance);
        return;
    }
    radiance[0] = radiance[1] = radiance[2] = 0.0f;
    if (!(lobe[0] > 0.0f)) return;
    const double s = std::log2(sharpness / kStackSharpnessMin) * env.levelsPerOctave - env.firstSharpnessIndex;
    const size_t k = std::min(size_t(std::max(0.0, std::floor(s))), stack.size() - 2);
    const float t = float(std::clamp(s - double(k), 0.0, 1.0));
    double w[3];
    mapDirection(env, lobe + 1, w);
    float below[3], above[3];
    bilinear(stack[k], w, below);
    bilinear(stack[k + 1], w, above);
    // Geometric in log lambda: exact for any mean radiance proportional to a power of lambda, so for a constant map
    // (power 0) and at the peak of a point light (power 1, where a linear blend is 6% off between octaves).
    const float scale = float(lobe[0] * kernelIntegral(sharpness));
    for (int c = 0; c < 3; ++c) {
        const float blend = below[c] > 0.0f && above[c] > 0.0f
                                ? below[c] * std::exp(t * std::log(above[c] / below[c]))
                                : (1.0f - t) * below[c] + t * above[c];
        radiance[c] = scale * blend;
    }
}

} // namespace prt
