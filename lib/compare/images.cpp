// prt compare --image: metrics over an image's mask, a false-colour relative-error picture with a legend, and a
// result | reference | error strip.
#include "compare.h"

#include "core.h"
#include "image.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace prt {

namespace {

double luminance(const float* rgb) {
    return kLuminance[0] * rgb[0] + kLuminance[1] * rgb[1] + kLuminance[2] * rgb[2];
}

// Viridis at five stops, interpolated linearly: dark blue (no error) to yellow (the top of the scale, and NaN).
void falseColour(double t, uint8_t out[3]) {
    static const double stops[5][3] = {{0.267, 0.005, 0.329}, {0.229, 0.322, 0.546}, {0.128, 0.567, 0.551},
                                       {0.369, 0.789, 0.383}, {0.993, 0.906, 0.144}};
    t = (t >= 0.0 ? std::min(t, 1.0) : std::isnan(t) ? 1.0 : 0.0) * 4.0;
    int i = std::min(3, int(t));
    double f = t - i;
    for (int c = 0; c < 3; ++c) out[c] = uint8_t(std::lround(255.0 * (stops[i][c] * (1 - f) + stops[i + 1][c] * f)));
}

constexpr uint8_t kOutsideMask[3] = {48, 48, 48};

// A 3x5 pixel font for the labels, one string of 15 cells per glyph, row by row.
const std::map<char, const char*>& glyphs() {
    static const std::map<char, const char*> font = {
        {'0', "###"
              "# #"
              "# #"
              "# #"
              "###"},
        {'1', " # "
              "## "
              " # "
              " # "
              "###"},
        {'2', "###"
              "  #"
              "###"
              "#  "
              "###"},
        {'3', "###"
              "  #"
              "###"
              "  #"
              "###"},
        {'4', "# #"
              "# #"
              "###"
              "  #"
              "  #"},
        {'5', "###"
              "#  "
              "###"
              "  #"
              "###"},
        {'6', "###"
              "#  "
              "###"
              "# #"
              "###"},
        {'7', "###"
              "  #"
              "  #"
              "  #"
              "  #"},
        {'8', "###"
              "# #"
              "###"
              "# #"
              "###"},
        {'9', "###"
              "# #"
              "###"
              "  #"
              "###"},
        {'%', "# #"
              "  #"
              " # "
              "#  "
              "# #"},
        {'.', "   "
              "   "
              "   "
              "   "
              " # "},
        {'+', "   "
              " # "
              "###"
              " # "
              "   "},
        {'R', "## "
              "# #"
              "## "
              "# #"
              "# #"},
        {'E', "###"
              "#  "
              "## "
              "#  "
              "###"},
        {'S', "###"
              "#  "
              "###"
              "  #"
              "###"},
        {'U', "# #"
              "# #"
              "# #"
              "# #"
              "###"},
        {'L', "#  "
              "#  "
              "#  "
              "#  "
              "###"},
        {'T', "###"
              " # "
              " # "
              " # "
              " # "},
        {'F', "###"
              "#  "
              "## "
              "#  "
              "#  "},
        {'N', "###"
              "# #"
              "# #"
              "# #"
              "# #"},
        {'C', "###"
              "#  "
              "#  "
              "#  "
              "###"},
        {'O', "###"
              "# #"
              "# #"
              "# #"
              "###"},
        {'A', "###"
              "# #"
              "###"
              "# #"
              "# #"},
        {'V', "# #"
              "# #"
              "# #"
              "# #"
              " # "},
        {'Y', "# #"
              "# #"
              " # "
              " # "
              " # "},
        {'M', "# #"
              "###"
              "###"
              "# #"
              "# #"},
        {'I', "###"
              " # "
              " # "
              " # "
              "###"},
    };
    return font;
}

constexpr int kScale = 2;                   // font pixels per glyph cell
constexpr int kGlyphWidth = 4 * kScale;     // 3 cells and a gap
constexpr int kLegendHeight = 12 + 5 * kScale + 8;

int textWidth(const std::string& text) { return int(text.size()) * kGlyphWidth; }

// Draws `text` (unknown glyphs are spaces) in white with its top-left corner at (x, y), clipped to the picture.
void drawText(Picture& picture, int x, int y, const std::string& text) {
    for (char ch : text) {
        auto glyph = glyphs().find(ch);
        if (glyph != glyphs().end())
            for (int cell = 0; cell < 15; ++cell) {
                if (glyph->second[cell] != '#') continue;
                for (int dy = 0; dy < kScale; ++dy)
                    for (int dx = 0; dx < kScale; ++dx) {
                        int px = x + (cell % 3) * kScale + dx, py = y + (cell / 3) * kScale + dy;
                        if (px < 0 || py < 0 || px >= picture.width || py >= picture.height) continue;
                        std::fill_n(&picture.rgb[(size_t(py) * picture.width + px) * 3], 3, uint8_t(255));
                    }
            }
        x += kGlyphWidth;
    }
}

std::string percent(double fraction) {
    char text[32];
    std::snprintf(text, sizeof text, "%g%%", 100.0 * fraction);
    return text;
}

// Copies `from` into `to` with its top-left corner at (x, y).
void paste(Picture& to, const Picture& from, int x, int y) {
    for (int row = 0; row < from.height; ++row)
        std::copy_n(&from.rgb[size_t(row) * from.width * 3], size_t(from.width) * 3,
                    &to.rgb[(size_t(y + row) * to.width + x) * 3]);
}

} // namespace

uint8_t toneMap(float radiance, float exposure) {
    double x = double(radiance) * std::exp2(double(exposure));
    if (!(x > 0.0)) return 0; // negative and NaN
    double display = x / (1.0 + x);
    double encoded = display <= 0.0031308 ? 12.92 * display : 1.055 * std::pow(display, 1.0 / 2.4) - 0.055;
    return uint8_t(std::lround(std::fmin(1.0, encoded) * 255.0));
}

ImageComparison compareImages(const float* result, const float* reference, const float* mask, int width,
                              int height) {
    ImageComparison comparison;
    comparison.width = width;
    comparison.height = height;
    const size_t pixels = size_t(width) * height;
    std::vector<float> a, b;
    double referenceLuminance = 0.0;
    for (size_t p = 0; p < pixels; ++p)
        if (!mask || mask[p] > 0.5f) {
            a.insert(a.end(), result + p * 3, result + p * 3 + 3);
            b.insert(b.end(), reference + p * 3, reference + p * 3 + 3);
            referenceLuminance += luminance(reference + p * 3);
        }
    comparison.maskPixels = a.size() / 3;
    comparison.metrics = compareRadiance(a.data(), b.data(), comparison.maskPixels);
    // The floor keeps near-black reference pixels from dominating: 1e-3 of the mean reference luminance.
    comparison.relativeFloor = comparison.maskPixels ? 1e-3 * referenceLuminance / double(comparison.maskPixels) : 0.0;
    comparison.relativeError.assign(pixels, -1.0f);
    std::vector<float> inside;
    for (size_t p = 0; p < pixels; ++p) {
        if (mask && !(mask[p] > 0.5f)) continue;
        double yb = luminance(reference + p * 3), ya = luminance(result + p * 3);
        double relative = std::fabs(ya - yb) / std::max(yb, comparison.relativeFloor);
        if (!(comparison.relativeFloor > 0.0)) relative = ya == yb ? 0.0 : 1.0;
        comparison.relativeError[p] = float(relative);
        inside.push_back(float(relative));
    }
    if (!inside.empty()) {
        double sum = 0.0;
        for (float e : inside) sum += e;
        comparison.meanRelativeError = sum / double(inside.size());
        std::sort(inside.begin(), inside.end());
        comparison.p95RelativeError = inside[std::min(inside.size() - 1, size_t(0.95 * double(inside.size())))];
        comparison.maxRelativeError = inside.back();
    }
    return comparison;
}

Picture relativeErrorPicture(const ImageComparison& comparison, double scaleTop) {
    Picture picture;
    picture.width = comparison.width; // labels that do not fit are clipped
    picture.height = comparison.height + kLegendHeight;
    picture.rgb.assign(size_t(picture.width) * picture.height * 3, 0);
    for (int y = 0; y < comparison.height; ++y)
        for (int x = 0; x < comparison.width; ++x) {
            float error = comparison.relativeError[size_t(y) * comparison.width + x];
            uint8_t* out = &picture.rgb[(size_t(y) * picture.width + x) * 3];
            if (error < 0.0f)
                std::copy_n(kOutsideMask, 3, out);
            else
                falseColour(error / scaleTop, out);
        }
    // The legend: a colour bar from 0 to scaleTop (and beyond, saturated), labelled at both ends.
    const int barTop = comparison.height + 4, barLeft = 8, barRight = picture.width - 8;
    for (int x = barLeft; x < barRight; ++x) {
        uint8_t colour[3];
        falseColour(double(x - barLeft) / double(barRight - barLeft - 1), colour);
        for (int y = barTop; y < barTop + 8; ++y) std::copy_n(colour, 3, &picture.rgb[(size_t(y) * picture.width + x) * 3]);
    }
    drawText(picture, barLeft, barTop + 10, "0%");
    std::string top = percent(scaleTop) + "+";
    drawText(picture, barRight - textWidth(top), barTop + 10, top);
    std::string middle = "REL. LUMINANCE ERROR";
    if (textWidth(middle) + textWidth(top) + textWidth("0%") + 16 < barRight - barLeft)
        drawText(picture, (picture.width - textWidth(middle)) / 2, barTop + 10, middle);
    return picture;
}

Picture tonemappedPicture(const float* radiance, int width, int height, float exposure) {
    Picture picture;
    picture.width = width;
    picture.height = height;
    picture.rgb.resize(size_t(width) * height * 3);
    for (size_t i = 0; i < picture.rgb.size(); ++i) picture.rgb[i] = toneMap(radiance[i], exposure);
    return picture;
}

Picture comparisonStrip(const Picture& result, const Picture& reference, const Picture& error) {
    const int gap = 4, labelHeight = 5 * kScale + 8;
    Picture strip;
    strip.width = result.width + reference.width + error.width + 2 * gap;
    strip.height = labelHeight + std::max({result.height, reference.height, error.height});
    strip.rgb.assign(size_t(strip.width) * strip.height * 3, 0);
    int x = 0;
    const Picture* panels[3] = {&result, &reference, &error};
    const char* labels[3] = {"RESULT", "REFERENCE", "ERROR"};
    for (int i = 0; i < 3; ++i) {
        drawText(strip, x + 4, 4, labels[i]);
        paste(strip, *panels[i], x, labelHeight);
        x += panels[i]->width + gap;
    }
    return strip;
}

} // namespace prt
