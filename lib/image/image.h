// Images and environment maps through OpenImageIO: float RGB in memory, validated on load.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace prt {

// A float RGB image, row-major, row 0 at the top, 3 floats per pixel, linear values.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<float> rgb;
};

// How an environment image maps to directions (docs/conventions.md).
enum class EnvLayout { Equirectangular, CubeStrip };

// Distant lighting: radiance per direction.
struct EnvironmentMap {
    EnvLayout layout = EnvLayout::Equirectangular;
    Image radiance;
};

// Before OpenImageIO opens an OpenEXR file: throws prt::Error(path, "OpenEXR header", ...) when an attribute
// declares more bytes than the file holds after it, or a name or the header list runs past the end. OpenEXR
// itself would allocate what the attribute declares. A file named .exr that is not OpenEXR is refused (OpenImageIO
// would read it with another format's reader); files of other formats pass unchecked. Both readers below and
// readImageChannels call it.
void checkExrHeaders(const std::string& path);

// Reads any image OpenImageIO reads, keeping the first three channels (grey is replicated).
// Throws prt::Error naming the file for: missing, not an image, unreadable pixels.
Image readImage(const std::string& path);

// Reads an environment map: 2:1 images are equirectangular, 1:6 images (or an EXR with envmap=cube) are
// cube strips. Throws prt::Error naming the file and the first bad texel (x, y, channel) for NaN, infinite or
// negative radiance, and for any other aspect ratio. Negative values no lower than -0.1 times the map's mean
// radiance are lossy-compression noise (DWA EXRs have them); they are set to 0 and logged. The returned
// radiance is finite and >= 0 everywhere.
EnvironmentMap readEnvironmentMap(const std::string& path);

// Channels of a multi-channel image picked by name: values [pixel][names.size()], row 0 at the top. 8-bit files
// read as q / 255, float and half files as stored.
struct ImageChannels {
    int width = 0;
    int height = 0;
    std::vector<float> values;
};
// Throws prt::Error naming the file for a missing or unreadable file, and naming the channel ("channel T003.G")
// when the file lacks one of `names`.
ImageChannels readImageChannels(const std::string& path, const std::vector<std::string>& names);

// The channel names of an image file in file order (OpenImageIO's: "R", "G", "B" for plain RGB files).
// Throws prt::Error naming the file when it cannot be opened.
std::vector<std::string> imageChannelNames(const std::string& path);

// Writes a float RGB image atomically (EXR as float or half by `half`, other formats by extension).
void writeImage(const std::string& path, const Image& image, bool half = false);

// How a written file stores its channel values; formats without it (PNG) take the nearest type they have.
enum class PixelStorage { U8, Half, Float };

// Writes `width` x `height` pixels of `channelNames.size()` interleaved channels atomically, the format from the
// path's extension (OpenEXR with ZIP compression; PNG for prt's 8-bit layers). `pixels` are floats ([0, 1] maps to
// 0..255 for U8 storage) or, in the second form, bytes stored as 8 bits. No header holds the time of writing, so the
// same pixels give the same bytes. Throws prt::Error(path, ..., kExitOutput) when it cannot write; `path` is untouched.
void writeImagePixels(const std::string& path, int width, int height, const std::vector<std::string>& channelNames,
                      const float* pixels, PixelStorage storage);
void writeImagePixels(const std::string& path, int width, int height, const std::vector<std::string>& channelNames,
                      const uint8_t* pixels);

} // namespace prt
