// OpenImageIO, loaded on first use: prt reads and writes image files through prt_oiio.so (oiio_module.cpp), which
// it dlopens the first time a function here runs. Nothing else in prt links OpenImageIO, so a process that never
// reads or writes an image (`prt run` computing cache keys, `prt --build-info`, `prt transfer --help`) starts
// without its ~260 shared libraries. Used by lib/image, lib/bake and lib/material; not installed.
//
// Where the module is looked for, first found wins (imageModuleCandidates):
//   1. DIR/prt_oiio.so, DIR the folder of the running executable (the build tree's root, where prt, prt-driver and
//      the prt-NAME stages are built);
//   2. DIR/../lib/prt/prt_oiio.so (an installed bin/ next to lib/prt/);
//   3. the build tree's prt_oiio.so, as an absolute path fixed at compile time (test programs in subfolders);
//   4. CMAKE_INSTALL_FULL_LIBDIR/prt/prt_oiio.so, fixed at compile time (an engine linking prt::runtime_images).
#pragma once

#include "image.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace prt {

// The file name of the module.
inline constexpr const char* kImageModuleName = "prt_oiio.so";

// The places above, in order, for an executable at `executable` (a path; "" for none: then 1 and 2 are left out).
std::vector<std::string> imageModuleCandidates(const std::string& executable);

// The first of imageModuleCandidates(executable) that is a regular file, or "" when none is. Loads nothing.
std::string findImageModule(const std::string& executable);

// An image opened through the module: its header read, its pixels not yet, so a caller bounds the size before it
// allocates. Empty (`handle` null) when opening failed.
struct OpenedImage {
    int width = 0;
    int height = 0;
    int channels = 0;
    bool deep = false;              // per-pixel sample lists, not a flat image
    bool cubeEnvironment = false;   // OpenEXR envmap=cube
    bool unassociatedAlpha = false; // the file says its alpha is not premultiplied
    std::vector<std::string> channelNames;
    std::shared_ptr<void> handle;   // closes the image when the last copy goes
};

// Opens an image file, or an encoded image in memory whose reader `nameHint`'s extension picks ("texture.png";
// `bytes` must outlive the result). On failure returns an empty OpenedImage and sets `error` to OpenImageIO's
// message. Throws prt::Error(kExitFailure) naming prt_oiio.so and every place looked in when the module cannot be
// loaded.
OpenedImage openImageFile(const std::string& path, std::string& error);
OpenedImage openImageMemory(const std::string& nameHint, const uint8_t* bytes, size_t size, std::string& error);

// Reads channels [0, channels) of every pixel, row 0 at the top, interleaved, into `pixels` (width * height *
// channels values, floats or, in the second form, bytes). `image` must be open and channels <= image.channels.
// Returns false and sets `error` when the pixels cannot be read.
bool readOpenedPixels(const OpenedImage& image, int channels, float* pixels, std::string& error);
bool readOpenedPixels(const OpenedImage& image, int channels, uint8_t* pixels, std::string& error);

// What writeImageFile returns.
enum class ImageWriteResult { Written, NoWriter, Failed };

// Writes width x height pixels of channelNames.size() interleaved channels to `tmpPath` in the format of
// `formatPath`'s extension, stored as `storage`; `pixels` floats, or bytes when `u8Pixels`.
// Sets `error` on failure. lib/image's writeImagePixels (atomic, checked) is the function to call.
ImageWriteResult writeImageFile(const std::string& formatPath, const std::string& tmpPath, int width, int height,
                                const std::vector<std::string>& channelNames, bool u8Pixels, const void* pixels,
                                PixelStorage storage, std::string& error);

// OpenImageIO's "threads" attribute (the fuzz harness sets 1). Loads the module.
void setImageLibraryThreads(int threads);

// The OpenImageIO version the loaded module was compiled against. Loads the module.
std::string imageLibraryVersion();

} // namespace prt
