// The luminance of linear RGB, written once: Rec. 709 / sRGB primaries, Y = 0.2126 R + 0.7152 G + 0.0722 B. Every
// luminance prt computes (error metrics, light extraction, importance sampling, FIV small sources) uses these.
#pragma once

namespace prt {

inline constexpr double kLuminance[3] = {0.2126, 0.7152, 0.0722};

} // namespace prt
