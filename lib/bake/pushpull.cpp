// Gutter filling: a push-pull pyramid (Gortler et al. 1996, with binary weights) and the thesis's one-ring dilation.
#include "bake.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace prt {

namespace {

// Rows in parallel; every texel is written by exactly one task, so results do not depend on scheduling.
template <class Body> void forRows(int height, Body body) {
    tbb::parallel_for(tbb::blocked_range<int>(0, height, 16), [&](const tbb::blocked_range<int>& rows) {
        for (int y = rows.begin(); y != rows.end(); ++y) body(y);
    });
}

// Channels per pass over the pyramid: bounds its memory to a few floats per texel whatever the channel count.
constexpr int kChunkChannels = 16;

struct Level {
    int width = 0, height = 0;
    std::vector<uint8_t> known; // some covered texel lies below
    std::vector<float> value;   // [texel][chunk channels]
};

// a + t (b - a): exactly a (= b) when a == b, so equal inputs interpolate to exactly themselves.
inline float lerp(float a, float b, float t) { return a + t * (b - a); }

} // namespace

void pushPull(float* texels, int width, int height, int channels, const uint8_t* covered) {
    // Which texels of each level have covered texels below: level 0 is `covered`, levels[i] is level i + 1.
    std::vector<Level> levels;
    for (int w = width, h = height; w > 1 || h > 1;) {
        Level parent;
        parent.width = (w + 1) / 2, parent.height = (h + 1) / 2;
        parent.known.assign(size_t(parent.width) * parent.height, 0);
        const uint8_t* child = levels.empty() ? covered : levels.back().known.data();
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                parent.known[size_t(y / 2) * parent.width + x / 2] |= child[size_t(y) * w + x];
        levels.push_back(std::move(parent));
        w = levels.back().width, h = levels.back().height;
    }
    if (levels.empty() || !levels.back().known[0]) return; // a 1x1 image, or nothing covered: nothing to pull from

    for (int first = 0; first < channels; first += kChunkChannels) {
        const int count = std::min(kChunkChannels, channels - first);
        // Pull: each known texel is the running mean of its known children (a running mean of equal values stays
        // exactly that value; a plain sum divided by the count need not).
        for (size_t i = 0; i < levels.size(); ++i) {
            Level& parent = levels[i];
            const Level* child = i > 0 ? &levels[i - 1] : nullptr;
            int cw = child ? child->width : width, ch = child ? child->height : height;
            parent.value.assign(size_t(parent.width) * parent.height * count, 0.0f);
            forRows(parent.height, [&](int y) {
                for (int x = 0; x < parent.width; ++x) {
                    size_t p = size_t(y) * parent.width + x;
                    if (!parent.known[p]) continue;
                    float* mean = &parent.value[p * count];
                    int n = 0;
                    for (int cy = 2 * y; cy < std::min(2 * y + 2, ch); ++cy)
                        for (int cx = 2 * x; cx < std::min(2 * x + 2, cw); ++cx) {
                            size_t c = size_t(cy) * cw + cx;
                            if (child ? !child->known[c] : !covered[c]) continue;
                            const float* value = child ? &child->value[c * count] : &texels[c * channels + first];
                            ++n;
                            for (int k = 0; k < count; ++k) mean[k] += (value[k] - mean[k]) / float(n);
                        }
                }
            });
        }
        // Push: from the 1x1 level down, each level's unknown texels interpolate the (by then complete) level above.
        for (int i = int(levels.size()) - 1; i >= 0; --i) {
            const Level& parent = levels[i];
            Level* child = i > 0 ? &levels[i - 1] : nullptr;
            int cw = child ? child->width : width, ch = child ? child->height : height;
            forRows(ch, [&](int y) {
                // Child centre y + 0.5 lies at parent coordinate (y + 0.5) / 2 - 0.5, between rows ya and yb.
                float fy = (y & 1) ? 0.25f : 0.75f;
                int ya = std::clamp((y - 1) >> 1, 0, parent.height - 1);
                int yb = std::clamp(((y - 1) >> 1) + 1, 0, parent.height - 1);
                for (int x = 0; x < cw; ++x) {
                    size_t c = size_t(y) * cw + x;
                    if (child ? child->known[c] : covered[c]) continue;
                    float fx = (x & 1) ? 0.25f : 0.75f;
                    int xa = std::clamp((x - 1) >> 1, 0, parent.width - 1);
                    int xb = std::clamp(((x - 1) >> 1) + 1, 0, parent.width - 1);
                    const float* p00 = &parent.value[(size_t(ya) * parent.width + xa) * count];
                    const float* p01 = &parent.value[(size_t(ya) * parent.width + xb) * count];
                    const float* p10 = &parent.value[(size_t(yb) * parent.width + xa) * count];
                    const float* p11 = &parent.value[(size_t(yb) * parent.width + xb) * count];
                    float* out = child ? &child->value[c * count] : &texels[c * channels + first];
                    for (int k = 0; k < count; ++k)
                        out[k] = lerp(lerp(p00[k], p01[k], fx), lerp(p10[k], p11[k], fx), fy);
                }
            });
        }
    }
}

void dilateOneRing(float* texels, int width, int height, int channels, const uint8_t* covered) {
    // Only empty texels change and only covered ones are read, so reading in place is reading the snapshot.
    forRows(height, [&](int y) {
        std::vector<double> sum(channels);
        for (int x = 0; x < width; ++x) {
            size_t t = size_t(y) * width + x;
            if (covered[t]) continue;
            std::fill(sum.begin(), sum.end(), 0.0);
            int count = 0;
            for (int ny = std::max(y - 1, 0); ny <= std::min(y + 1, height - 1); ++ny)
                for (int nx = std::max(x - 1, 0); nx <= std::min(x + 1, width - 1); ++nx) {
                    size_t n = size_t(ny) * width + nx;
                    if (!covered[n]) continue;
                    ++count;
                    for (int k = 0; k < channels; ++k) sum[k] += texels[n * channels + k];
                }
            if (count == 0) continue;
            for (int k = 0; k < channels; ++k) texels[t * channels + k] = float(sum[k] / count);
        }
    });
}

} // namespace prt
