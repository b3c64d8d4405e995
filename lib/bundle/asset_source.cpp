// A scene asset's glTF model made self-contained, so that a scene bundle writes it as one .glb.
#include "bundle_internal.h"

#include "core.h"

#include <set>

namespace prt::detail {

std::shared_ptr<const tinygltf::Model> selfContainedModel(tinygltf::Model model) {
    std::vector<unsigned char> merged;
    std::vector<size_t> base(model.buffers.size());
    for (size_t b = 0; b < model.buffers.size(); ++b) {
        merged.resize((merged.size() + 7) / 8 * 8, 0); // keeps every accessor's component alignment
        base[b] = merged.size();
        merged.insert(merged.end(), model.buffers[b].data.begin(), model.buffers[b].data.end());
    }
    for (tinygltf::BufferView& view : model.bufferViews) {
        if (view.buffer >= 0 && size_t(view.buffer) < base.size()) view.byteOffset += base[size_t(view.buffer)];
        view.buffer = 0;
    }
    for (tinygltf::Image& image : model.images) {
        if (image.bufferView < 0 && !image.image.empty()) {
            merged.resize((merged.size() + 7) / 8 * 8, 0);
            tinygltf::BufferView view;
            view.buffer = 0;
            view.byteOffset = merged.size();
            view.byteLength = image.image.size();
            merged.insert(merged.end(), image.image.begin(), image.image.end());
            model.bufferViews.push_back(view);
            image.bufferView = int(model.bufferViews.size()) - 1;
        }
        if (image.mimeType.empty() && image.image.size() >= 3)
            image.mimeType = image.image[0] == 0x89 ? "image/png" : image.image[0] == 0xFF ? "image/jpeg" : "";
        image.uri.clear();
        image.image.clear();
        image.as_is = false;
        image.width = image.height = image.component = image.bits = image.pixel_type = -1;
    }
    merged.resize((merged.size() + 3) / 4 * 4, 0);
    tinygltf::Buffer buffer;
    buffer.data = std::move(merged);
    if (!model.buffers.empty()) {
        buffer.name = model.buffers[0].name;
        buffer.extras = model.buffers[0].extras;
    }
    model.buffers.assign(1, std::move(buffer));
    model.extensions.erase(kBundleExtension);
    std::erase(model.extensionsUsed, std::string(kBundleExtension));
    std::erase(model.extensionsRequired, std::string(kBundleExtension));
    model.extensions_json_string.clear();
    return std::make_shared<const tinygltf::Model>(std::move(model));
}

} // namespace prt::detail

namespace prt {

std::vector<PrimitiveTriangles> primitivesWithoutNormals(const Bundle& bundle, const std::string& file) {
    const tinygltf::Model& model = *bundle.asset->source;
    std::vector<PrimitiveTriangles> out;
    std::set<std::pair<int, int>> seen;
    for (const SceneReceiver& receiver : bundle.asset->receivers) {
        const tinygltf::Primitive& primitive = model.meshes[size_t(receiver.mesh)].primitives[size_t(receiver.primitive)];
        if (!seen.insert({receiver.mesh, receiver.primitive}).second) continue;
        auto anyZero = [](const std::vector<float>& normals, size_t first, size_t count) {
            for (size_t i = 3 * first; i < 3 * (first + count); i += 3)
                if (normals[i] == 0.0f && normals[i + 1] == 0.0f && normals[i + 2] == 0.0f) return true;
            return false;
        };
        const bool authored = primitive.attributes.count("NORMAL") > 0;
        // The flattened rows already hold this placement's normals: a zero vector stays zero in world space and a
        // non-zero one stays non-zero under any invertible transform, so only a primitive with a zero row is read.
        const std::vector<float>& rows = bundle.mesh.normals;
        if (authored && !rows.empty() && !anyZero(rows, receiver.firstVertex, receiver.vertexCount)) continue;
        TriMesh triangles = detail::readGltfPrimitive(model, receiver.mesh, receiver.primitive, file);
        if (authored && !anyZero(triangles.normals, 0, triangles.normals.size() / 3)) continue;
        out.push_back({receiver.mesh, receiver.primitive, std::move(triangles)});
    }
    return out;
}

Bundle withPrimitiveNormals(const Bundle& bundle, const std::vector<PrimitiveTriangles>& normals, const std::string& file) {
    tinygltf::Model model = *bundle.asset->source;
    std::vector<unsigned char>& buffer = model.buffers[0].data;
    for (const PrimitiveTriangles& p : normals) {
        const std::vector<float>& n = p.triangles.normals;
        tinygltf::Primitive& primitive = model.meshes[size_t(p.mesh)].primitives[size_t(p.primitive)];
        const tinygltf::Accessor& position = model.accessors[size_t(primitive.attributes.at("POSITION"))];
        if (n.size() != 3 * position.count)
            throw Error(file, "meshes[" + std::to_string(p.mesh) + "].primitives[" + std::to_string(p.primitive) + "]",
                        "normals do not match the vertex count", kExitFailure);
        buffer.resize((buffer.size() + 3) / 4 * 4, 0);
        tinygltf::BufferView view;
        view.buffer = 0;
        view.byteOffset = buffer.size();
        view.byteLength = n.size() * sizeof(float);
        view.target = TINYGLTF_TARGET_ARRAY_BUFFER;
        const unsigned char* bytes = reinterpret_cast<const unsigned char*>(n.data());
        buffer.insert(buffer.end(), bytes, bytes + view.byteLength);
        model.bufferViews.push_back(view);
        tinygltf::Accessor accessor;
        accessor.bufferView = int(model.bufferViews.size()) - 1;
        accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
        accessor.type = TINYGLTF_TYPE_VEC3;
        accessor.count = position.count;
        model.accessors.push_back(accessor);
        primitive.attributes["NORMAL"] = int(model.accessors.size()) - 1;
    }
    buffer.resize((buffer.size() + 3) / 4 * 4, 0);
    Bundle out;
    out.producer = bundle.producer;
    out.inputs = bundle.inputs;
    out.convention = bundle.convention;
    out.layers = bundle.layers;
    auto asset = std::make_shared<SceneAsset>();
    asset->sourceJson = bundle.asset->sourceJson;
    out.mesh = detail::readGltfScene(model, file, *asset);
    asset->source = detail::selfContainedModel(std::move(model));
    out.asset = std::move(asset);
    return out;
}

} // namespace prt
