// Writing images atomically through OpenImageIO.
#include "image.h"

#include "core.h"

#include <OpenImageIO/imageio.h>

namespace prt {

void writeImage(const std::string& path, const Image& image, bool half) {
    if (image.width <= 0 || image.height <= 0 || image.rgb.size() != size_t(image.width) * image.height * 3)
        throw Error(path, "", "image to write has inconsistent size", kExitFailure);

    writeFileAtomic(path, [&](const std::string& tmpPath) {
        // The temporary name hides the extension, so the format comes from the final path.
        auto output = OIIO::ImageOutput::create(path);
        if (!output)
            throw Error(path, "", "no image writer for this extension (" + OIIO::geterror() + ")", kExitOutput);
        bool exr = std::string(output->format_name()) == "openexr";
        // Formats without float storage (PNG, JPEG) take the nearest type they support.
        OIIO::TypeDesc storage = exr && half ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT;
        OIIO::ImageSpec spec(image.width, image.height, 3, storage);
        if (exr) spec.attribute("compression", "zip");
        // OIIO would stamp the current time (EXR capDate): a fixed one keeps same pixels, same bytes.
        spec.attribute("DateTime", "1970:01:01 00:00:00");
        if (!output->open(tmpPath, spec) || !output->write_image(OIIO::TypeDesc::FLOAT, image.rgb.data()) ||
            !output->close())
            throw Error(path, "", "cannot write image (" + output->geterror() + ")", kExitOutput);
    });
}

} // namespace prt
