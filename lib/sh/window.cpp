// Band windows that trade sharpness for less ringing, and per-band energy.
#include "sh.h"

#include "core.h"

#include <cmath>
#include <numbers>

namespace prt::sh {

Window parseWindow(const std::string& name, const char* option) {
    if (name == "none") return Window::None;
    if (name == "hann") return Window::Hann;
    if (name == "lanczos") return Window::Lanczos;
    throw Error("", option, "unknown window '" + name + "' (need none, hann or lanczos)", kExitUsage);
}

const char* windowName(Window window) {
    switch (window) {
    case Window::Hann: return "hann";
    case Window::Lanczos: return "lanczos";
    case Window::None: break;
    }
    return "none";
}

double windowWeight(Window window, int l, int order) {
    double t = double(l) / double(order);
    switch (window) {
    case Window::Hann: return 0.5 * (1.0 + std::cos(std::numbers::pi * t));
    case Window::Lanczos: return l == 0 ? 1.0 : std::sin(std::numbers::pi * t) / (std::numbers::pi * t);
    case Window::None: break;
    }
    return 1.0;
}

void applyWindow(Window window, int order, float* coeffs, int channels) {
    for (int l = 0; l < order; ++l) {
        float weight = float(windowWeight(window, l, order));
        for (int i = l * l * channels; i < (l + 1) * (l + 1) * channels; ++i) coeffs[i] *= weight;
    }
}

std::vector<double> bandEnergy(int order, const float* coeffs, int channels) {
    std::vector<double> energy(order, 0.0);
    for (int l = 0; l < order; ++l)
        for (int i = l * l * channels; i < (l + 1) * (l + 1) * channels; ++i)
            energy[l] += double(coeffs[i]) * coeffs[i];
    return energy;
}

} // namespace prt::sh
