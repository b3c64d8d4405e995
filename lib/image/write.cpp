// Writing images atomically through OpenImageIO (loaded on first use, image_library.h).
#include "image.h"

#include "core.h"
#include "image_library.h"

namespace prt {

namespace {

void writePixels(const std::string& path, int width, int height, const std::vector<std::string>& channelNames,
                 const void* pixels, bool u8Pixels, PixelStorage storage) {
    if (width <= 0 || height <= 0 || channelNames.empty())
        throw Error(path, "", "image to write has no pixels or no channels", kExitFailure);
    writeFileAtomic(path, [&](const std::string& tmpPath) {
        std::string error;
        // The temporary name hides the extension, so the format comes from the final path.
        switch (writeImageFile(path, tmpPath, width, height, channelNames, u8Pixels, pixels, storage, error)) {
        case ImageWriteResult::Written: return;
        case ImageWriteResult::NoWriter:
            throw Error(path, "", "no image writer for this extension (" + error + ")", kExitOutput);
        case ImageWriteResult::Failed: throw Error(path, "", "cannot write image (" + error + ")", kExitOutput);
        }
    });
}

} // namespace

void writeImagePixels(const std::string& path, int width, int height, const std::vector<std::string>& channelNames,
                      const float* pixels, PixelStorage storage) {
    writePixels(path, width, height, channelNames, pixels, false, storage);
}

void writeImagePixels(const std::string& path, int width, int height, const std::vector<std::string>& channelNames,
                      const uint8_t* pixels) {
    writePixels(path, width, height, channelNames, pixels, true, PixelStorage::U8);
}

void writeImage(const std::string& path, const Image& image, bool half) {
    if (image.width <= 0 || image.height <= 0 || image.rgb.size() != size_t(image.width) * image.height * 3)
        throw Error(path, "", "image to write has inconsistent size", kExitFailure);
    writeImagePixels(path, image.width, image.height, {"R", "G", "B"}, image.rgb.data(),
                     half ? PixelStorage::Half : PixelStorage::Float);
}

} // namespace prt
