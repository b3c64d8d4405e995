// prt/texels.h: per-texel transfer of a `prt bake` bundle as a RelightModel. Part of prt::runtime (std and the
// bundle reader only), except loadTexelRelightModel, which lives in prt::runtime_images (OpenImageIO).
#pragma once

#include "relight.h"

#include <string>

namespace prt {

// Per-texel transfer ready to relight: the "texel_transfer" layer of a bundle and the coefficient texture it
// references. Rows are texels, row-major with row 0 at the top of the atlas (docs/bundle.md, "Texel layers"), so
// the per-vertex kernel relights them unchanged. A scene's bake (docs/bundle.md "Scene bakes") holds irradiance
// transfer: rows.albedoExcluded is set and rows.albedo left empty, so its texels relight to E / pi, what a white
// surface reflects, which an engine multiplies by its base colour per pixel (the layer "lightmap_uv" addresses them).
struct TexelRelightModel {
    int width = 0, height = 0;
    RelightModel rows; // rows.vertexCount = width * height texels
};

// Takes the "texel_transfer" layer out of `bundle` when its rows are stored in the bundle's own buffers (layer data
// present, no params.uri). Part of the thin prt::runtime. Needs: domain "texel", semantic "sh_transfer_rgb", shape
// [W*H, L*L, 3] with params width W and height H (and params.order = L when set), W*H*L*L*3 finite values.
// Throws prt::Error naming `source` otherwise, and for a layer whose texels live in a texture (params.uri), which
// loadTexelRelightModel reads.
TexelRelightModel texelRelightModel(Bundle bundle, const std::string& source);

// prt::runtime_images only (links OpenImageIO). Reads the bundle's "texel_transfer" layer and its texture:
// params.uri, relative to the bundle file (symlinks resolved), is an OpenEXR with channels T000.R, T000.G, ...
// (params.format "half" or "float") or the JSON sidecar of 8-bit PNG layers (format "u8": value = min + q * (max -
// min) / 255 per coefficient layer); a layer with no params.uri is read from the bundle as texelRelightModel does.
// Needs what texelRelightModel needs, texture files whose xxh128 equals the recorded hash and of W x H texels,
// finite values. Throws prt::Error naming the bundle or the texture file, the place and the problem otherwise.
TexelRelightModel loadTexelRelightModel(const std::string& bundlePath);

// Channel name of coefficient j, colour c (0..2) in coefficient textures: "T000.R", "T012.B".
std::string texelCoefficientChannel(int coefficient, int colour);


} // namespace prt
