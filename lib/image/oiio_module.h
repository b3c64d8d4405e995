// The C interface between prt and prt_oiio.so, the one binary that links OpenImageIO (oiio_module.cpp). prt loads
// the module with dlopen the first time it reads or writes an image (image_library.cpp), so a process that never
// touches an image never maps OpenImageIO's ~260 shared libraries. Plain C types only: the table is read across a
// dlopen boundary. Not installed; prt code uses image_library.h, never this header.
#pragma once

#include <stddef.h>

extern "C" {

// Bumped whenever a field of PrtOiioModule changes; the loader refuses a module of another number.
#define PRT_OIIO_ABI 1

// The symbol the loader looks up.
#define PRT_OIIO_ENTRY "prt_oiio_module"

// What an opened image's header says (subimage 0).
struct PrtImageHeader {
    int width;
    int height;
    int channels;
    int deep;              // 1: per-pixel sample lists (deep OpenEXR), not a flat image
    int cubeEnvironment;   // 1: OpenEXR envmap=cube (OpenImageIO's "CubeFace Environment" texture format)
    int unassociatedAlpha; // 1: the file says its alpha is not premultiplied (oiio:UnassociatedAlpha)
};

// Every entry point returns 0 / null on failure and writes OpenImageIO's message, truncated and NUL-terminated,
// to error[0 .. errorSize); 1 / non-null on success.
struct PrtOiioModule {
    int abi;                  // PRT_OIIO_ABI of the module's build
    const char* version;      // OIIO_VERSION_STRING of the headers the module was compiled against
    // OpenImageIO's "threads" attribute (0: one per core, its default).
    void (*setThreads)(int threads);
    // Opens an image file, reads its header into `header`; returns a handle for readPixels / channelName / close.
    void* (*openFile)(const char* path, PrtImageHeader* header, char* error, size_t errorSize);
    // The same for an encoded image in memory; `nameHint` ("texture.png") picks the reader by its extension.
    // `bytes` must outlive the handle.
    void* (*openMemory)(const char* nameHint, const unsigned char* bytes, size_t size, PrtImageHeader* header,
                        char* error, size_t errorSize);
    // The name of channel `channel` (0 <= channel < header.channels) of an opened image; valid until close.
    const char* (*channelName)(void* image, int channel);
    // Reads channels [0, channels) of every pixel, row 0 at the top, interleaved, into `pixels`: floats, or bytes
    // when `u8` is 1. `pixels` holds width * height * channels of them.
    int (*readPixels)(void* image, int channels, int u8, void* pixels, char* error, size_t errorSize);
    void (*close)(void* image);
    // Writes width x height pixels of `channels` interleaved channels named `channelNames` to `tmpPath`, in the
    // format `formatPath`'s extension names (OpenEXR: ZIP compression and a fixed DateTime, so the same pixels
    // give the same bytes). `pixels` are floats, or bytes when `u8Pixels` is 1; `storage` is 0 (8-bit), 1 (half)
    // or 2 (float). Returns 1 on success, 0 when no writer handles the extension, -1 when writing failed.
    int (*write)(const char* formatPath, const char* tmpPath, int width, int height, int channels,
                 const char* const* channelNames, int u8Pixels, const void* pixels, int storage, char* error,
                 size_t errorSize);
};

// The module's one exported function: its table, valid for the life of the process.
typedef const PrtOiioModule* (*PrtOiioEntry)(void);

} // extern "C"
