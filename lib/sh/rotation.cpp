// Rotation of SH coefficient vectors by the Ivanic-Ruedenberg recurrence (J. Phys. Chem. 1996, with the 1998
// erratum). Without the Condon-Shortley phase, band 1 is R itself with rows and columns reordered to (y, z, x),
// and the recurrence builds every higher band from band 1 and the band below with no sign changes
// (tests/sh/rotation_test.cpp checks each band against projecting the rotated function).
#include "sh.h"

#include "core.h"

#include <cmath>
#include <numbers>

namespace prt::sh {

namespace {

// Band `l` of the rotation, entries indexed by m, n in -l..l.
struct Band {
    double* data;
    int l;
    double& operator()(int m, int n) const { return data[(m + l) * (2 * l + 1) + (n + l)]; }
};

// The function P of Ivanic-Ruedenberg: band 1 `r1` combined with band l-1 `prev` for entry (a, b) of band l.
double combine(int i, int a, int b, int l, const Band& r1, const Band& prev) {
    if (b == l) return r1(i, 1) * prev(a, l - 1) - r1(i, -1) * prev(a, -l + 1);
    if (b == -l) return r1(i, 1) * prev(a, -l + 1) + r1(i, -1) * prev(a, l - 1);
    return r1(i, 0) * prev(a, b);
}

void buildBand(const Band& band, const Band& r1, const Band& prev) {
    int l = band.l;
    for (int m = -l; m <= l; ++m)
        for (int n = -l; n <= l; ++n) {
            int am = std::abs(m);
            double zero = m == 0 ? 1.0 : 0.0;
            double denominator = std::abs(n) == l ? double(2 * l) * (2 * l - 1) : double(l + n) * (l - n);
            double u = std::sqrt(double(l + m) * (l - m) / denominator);
            double v = 0.5 * std::sqrt((1.0 + zero) * (l + am - 1) * (l + am) / denominator) * (1.0 - 2.0 * zero);
            double w = -0.5 * std::sqrt(double(l - am - 1) * (l - am) / denominator) * (1.0 - zero);

            // u and w vanish exactly where their P terms would reach outside band l-1.
            double value = 0.0;
            if (u != 0.0) value += u * combine(0, m, n, l, r1, prev);
            if (v != 0.0) {
                double term;
                if (m == 0)
                    term = combine(1, 1, n, l, r1, prev) + combine(-1, -1, n, l, r1, prev);
                else if (m > 0)
                    term = combine(1, m - 1, n, l, r1, prev) * (m == 1 ? std::numbers::sqrt2 : 1.0) -
                           (m == 1 ? 0.0 : combine(-1, -m + 1, n, l, r1, prev));
                else
                    term = (m == -1 ? 0.0 : combine(1, m + 1, n, l, r1, prev)) +
                           combine(-1, -m - 1, n, l, r1, prev) * (m == -1 ? std::numbers::sqrt2 : 1.0);
                value += v * term;
            }
            if (w != 0.0) {
                double term = m > 0 ? combine(1, m + 1, n, l, r1, prev) + combine(-1, -m - 1, n, l, r1, prev)
                                    : combine(1, m - 1, n, l, r1, prev) - combine(-1, -m + 1, n, l, r1, prev);
                value += w * term;
            }
            band(m, n) = value;
        }
}

template <typename T>
void rotateCoefficients(const Rotation& rotation, const T* in, T* out, int channels) {
    size_t offset = 0;
    for (int l = 0; l < rotation.order; ++l) {
        int size = 2 * l + 1, first = l * l;
        const double* block = rotation.blocks.data() + offset;
        for (int row = 0; row < size; ++row)
            for (int c = 0; c < channels; ++c) {
                double sum = 0.0;
                for (int column = 0; column < size; ++column)
                    sum += block[row * size + column] * double(in[(first + column) * channels + c]);
                out[(first + row) * channels + c] = T(sum);
            }
        offset += size_t(size) * size;
    }
}

} // namespace

Rotation rotation(int order, const double R[9]) {
    if (order < 1 || order > kMaxOrder)
        throw Error("", "sh::rotation", "order " + std::to_string(order) + " outside 1.." + std::to_string(kMaxOrder),
                    kExitFailure);
    Rotation result;
    result.order = order;
    size_t total = 0;
    for (int l = 0; l < order; ++l) total += size_t(2 * l + 1) * (2 * l + 1);
    result.blocks.assign(total, 0.0);

    result.blocks[0] = 1.0;
    if (order == 1) return result;
    // Y_1,m for m = -1, 0, 1 is proportional to y, z, x.
    Band r1{result.blocks.data() + 1, 1};
    const int axis[3] = {1, 2, 0};
    for (int m = -1; m <= 1; ++m)
        for (int n = -1; n <= 1; ++n) r1(m, n) = R[axis[m + 1] * 3 + axis[n + 1]];

    Band prev = r1;
    for (int l = 2; l < order; ++l) {
        Band band{prev.data + (2 * l - 1) * (2 * l - 1), l};
        buildBand(band, r1, prev);
        prev = band;
    }
    return result;
}

void rotate(const Rotation& rotation, const float* in, float* out, int channels) {
    rotateCoefficients(rotation, in, out, channels);
}
void rotate(const Rotation& rotation, const double* in, double* out, int channels) {
    rotateCoefficients(rotation, in, out, channels);
}

void rotationY(double degrees, double R[9]) {
    double angle = degrees * std::numbers::pi / 180.0;
    double c = std::cos(angle), s = std::sin(angle);
    const double matrix[9] = {c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c};
    for (int i = 0; i < 9; ++i) R[i] = matrix[i];
}

} // namespace prt::sh
