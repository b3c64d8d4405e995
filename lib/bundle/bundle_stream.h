// Streaming bundles: a bundle read as its description (meshes, records, every layer's shape and parameters) and
// the place of each layer's stored bytes in the file, without those bytes; and writeBundle for layers whose stored
// bytes come from the caller in pieces. Together they join or copy layers of any size in bounded memory: `prt merge`
// (lib/pipeline), the bake's merge (lib/bake). docs/bundle.md is the format; docs/pipelines.md "Shards" the use.
#pragma once

#include "bundle.h"

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace prt {

// Where a layer's stored bytes lie in a bundle file (docs/bundle.md "File layout"), and their hash as
// readBundleHeader read them.
struct LayerExtent {
    uint64_t offset = 0;     // from the start of the file
    uint64_t byteLength = 0; // component size x elements; 0 for a layer without a bufferView
    std::string hash;        // hashBytes of the byteLength bytes at offset
};

// A bundle file without its layers' values.
struct BundleHeader {
    std::string path;
    Bundle bundle;                    // everything readBundle gives, but every layer's data and integers empty
    std::vector<LayerExtent> extents; // extents[i] for bundle.layers[i]
};

// Reads a .glb bundle as readBundle does, with every check readBundle makes (the checksum over the whole binary
// chunk included), but keeps no layer values: it streams the binary chunk once in 1 MiB pieces and holds only the
// bytes before the first layer view (the meshes, or a scene's asset). Needs a .glb whose layer views lie after
// every other view (writeBundle lays bundles out so); throws prt::Error(path, ...) (kExitInput) for another layout
// and for whatever readBundle refuses.
BundleHeader readBundleHeader(const std::string& path);

// Receives consecutive pieces of stored bytes.
using ByteSink = std::function<void(const void* bytes, size_t size)>;

// Passes the stored bytes of layer `index` of `header` to `sink` in order, in pieces of at most 1 MiB, reading the
// file by ranges. Throws prt::Error(header.path, "layer NAME", kExitInput) when they cannot be read or are not the
// bytes readBundleHeader hashed (the file changed since). That check ends the pass, so `sink` must write into
// something the throw discards (writeFileAtomic's temporary file, a buffer).
void streamLayerBytes(const BundleHeader& header, size_t index, const ByteSink& sink);

// streamLayerBytes decoded into `values` (for float32 and float16 layers): exactly the layer's element count of
// floats, as readBundle's Layer::data. Throws as streamLayerBytes, and prt::Error(kExitInput) for another type.
void readLayerFloats(const BundleHeader& header, size_t index, float* values);

// Layer `index` of `header` with its values, as readBundle gives it: `layer` (that layer of header.bundle, or a copy
// of it) gets its data (float layers) or integers (the others), decoded from the stored bytes read by ranges; a layer
// without a bufferView stays empty. Throws as streamLayerBytes.
void readLayerValues(const BundleHeader& header, size_t index, Layer& layer);

// A layer's stored bytes for writeBundleStreamed: `write` passes exactly byteLength of them to its sink, in order.
struct LayerStream {
    uint64_t byteLength = 0;
    std::function<void(const ByteSink& sink)> write;
};

// writeBundle for layers given as streams: where streams[i].write is set, bundle.layers[i] holds no values (its
// shape, componentType and params describe them) and streams[i] gives its stored bytes, which must number the
// component size times the elements of its shape; other layers keep their values in memory. streams is empty or
// holds one entry per layer. The file is the one writeBundle writes for the same bundle with those values in
// memory, byte for byte, written atomically. Memory: the meshes, the JSON and a few MiB besides the in-memory
// layers; no layer is copied whole. Throws as writeBundle, and prt::Error(kExitFailure) when a stream gives
// another number of bytes than it declares or a float16 value that is not finite; `path` is then untouched.
void writeBundleStreamed(const std::string& path, const Bundle& bundle, const std::vector<LayerStream>& streams,
                         int version = kBundleVersion);

} // namespace prt
