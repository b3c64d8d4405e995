#include "bundle_internal.h"

#include "core.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

namespace prt::detail {
namespace {

// Column-major 4x4, glTF's layout for node matrices.
using Matrix = std::array<double, 16>;
constexpr Matrix kIdentity = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

Matrix multiply(const Matrix& a, const Matrix& b) {
    Matrix product{};
    for (int column = 0; column < 4; ++column)
        for (int row = 0; row < 4; ++row)
            for (int k = 0; k < 4; ++k) product[column * 4 + row] += a[k * 4 + row] * b[column * 4 + k];
    return product;
}

// The node's transform relative to its parent: its matrix, or translation * rotation * scale.
Matrix localMatrix(const tinygltf::Node& node) {
    Matrix m = kIdentity;
    if (node.matrix.size() == 16) {
        std::copy(node.matrix.begin(), node.matrix.end(), m.begin());
        return m;
    }
    if (node.rotation.size() == 4) {
        double x = node.rotation[0], y = node.rotation[1], z = node.rotation[2], w = node.rotation[3];
        m = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),     0,
             2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),     0,
             2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y), 0,
             0,                       0,                       0,                       1};
    }
    if (node.scale.size() == 3)
        for (int column = 0; column < 3; ++column)
            for (int row = 0; row < 3; ++row) m[column * 4 + row] *= node.scale[column];
    if (node.translation.size() == 3)
        for (int row = 0; row < 3; ++row) m[12 + row] = node.translation[row];
    return m;
}

// Where an accessor's elements lie, after checking that all of them are inside its buffer view and buffer.
struct Elements {
    const unsigned char* first = nullptr;
    size_t stride = 0;
    size_t count = 0;
    int componentType = 0;
    int type = 0;
    bool normalized = false;
};

Elements locate(const tinygltf::Model& model, int index, const std::string& file, const std::string& place) {
    auto refuse = [&](const std::string& problem) { throw Error(file, place, problem); };
    if (index < 0 || size_t(index) >= model.accessors.size()) refuse("accessor " + std::to_string(index) + " does not exist");
    const tinygltf::Accessor& accessor = model.accessors[index];
    if (accessor.sparse.isSparse) refuse("sparse accessors are not supported");
    if (accessor.bufferView < 0 || size_t(accessor.bufferView) >= model.bufferViews.size())
        refuse("accessor has no valid buffer view");
    const tinygltf::BufferView& view = model.bufferViews[accessor.bufferView];
    if (view.buffer < 0 || size_t(view.buffer) >= model.buffers.size()) refuse("buffer view has no valid buffer");
    const std::vector<unsigned char>& buffer = model.buffers[view.buffer].data;
    int componentSize = tinygltf::GetComponentSizeInBytes(uint32_t(accessor.componentType));
    int components = tinygltf::GetNumComponentsInType(uint32_t(accessor.type));
    if (componentSize <= 0 || components <= 0) refuse("unknown component or element type");
    size_t elementSize = size_t(componentSize) * size_t(components);
    size_t stride = view.byteStride ? view.byteStride : elementSize;
    if (stride < elementSize) refuse("byte stride is smaller than one element");
    if (view.byteOffset > buffer.size() || view.byteLength > buffer.size() - view.byteOffset)
        refuse("buffer view reaches past the end of its buffer");
    Elements elements{nullptr, stride, accessor.count, accessor.componentType, accessor.type, accessor.normalized};
    if (accessor.count == 0) return elements;
    if (accessor.byteOffset > view.byteLength || view.byteLength - accessor.byteOffset < elementSize ||
        accessor.count - 1 > (view.byteLength - accessor.byteOffset - elementSize) / stride)
        refuse("accessor reaches past the end of its buffer view");
    elements.first = buffer.data() + view.byteOffset + accessor.byteOffset;
    return elements;
}

// One component as a number; normalized integers map to [0, 1] or [-1, 1] by glTF's rule.
double component(const unsigned char* bytes, int componentType, bool normalized) {
    auto load = [bytes](auto value) {
        std::memcpy(&value, bytes, sizeof(value));
        return value;
    };
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return load(float());
    case TINYGLTF_COMPONENT_TYPE_DOUBLE: return load(double());
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return load(uint8_t()) / (normalized ? 255.0 : 1.0);
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return load(uint16_t()) / (normalized ? 65535.0 : 1.0);
    case TINYGLTF_COMPONENT_TYPE_BYTE: return normalized ? std::max(load(int8_t()) / 127.0, -1.0) : load(int8_t());
    case TINYGLTF_COMPONENT_TYPE_SHORT: return normalized ? std::max(load(int16_t()) / 32767.0, -1.0) : load(int16_t());
    default: return load(uint32_t());
    }
}

// Appends the first `width` components of each element of vector accessor `index` to `out` as floats (COLOR_0
// may be RGBA: alpha is dropped). Returns the element count.
size_t appendFloats(const tinygltf::Model& model, int index, int width, std::vector<float>& out, const std::string& file,
                    const std::string& place) {
    Elements elements = locate(model, index, file, place);
    int components = tinygltf::GetNumComponentsInType(uint32_t(elements.type));
    bool isVector = elements.type == TINYGLTF_TYPE_VEC2 || elements.type == TINYGLTF_TYPE_VEC3 || elements.type == TINYGLTF_TYPE_VEC4;
    if (!isVector || components < width) throw Error(file, place, "needs a vector of at least " + std::to_string(width) + " components");
    int componentSize = tinygltf::GetComponentSizeInBytes(uint32_t(elements.componentType));
    for (size_t i = 0; i < elements.count; ++i)
        for (int c = 0; c < width; ++c)
            out.push_back(float(component(elements.first + i * elements.stride + c * componentSize, elements.componentType,
                                          elements.normalized)));
    return elements.count;
}

// COLOR_0 (VEC3 or VEC4, float or normalized integers) as RGBA, alpha 1 for VEC3. Returns the element count.
size_t appendColors(const tinygltf::Model& model, int index, std::vector<float>& rgba, const std::string& file,
                    const std::string& place) {
    Elements elements = locate(model, index, file, place);
    if (elements.type != TINYGLTF_TYPE_VEC3 && elements.type != TINYGLTF_TYPE_VEC4)
        throw Error(file, place, "COLOR_0 must be VEC3 or VEC4");
    int width = elements.type == TINYGLTF_TYPE_VEC4 ? 4 : 3;
    std::vector<float> values;
    appendFloats(model, index, width, values, file, place);
    rgba.reserve(rgba.size() + 4 * elements.count);
    for (size_t i = 0; i < elements.count; ++i)
        for (int c = 0; c < 4; ++c) rgba.push_back(c < width ? values[width * i + c] : 1.0f);
    return elements.count;
}

std::vector<uint32_t> readIndices(const tinygltf::Model& model, int index, const std::string& file, const std::string& place) {
    Elements elements = locate(model, index, file, place);
    bool integer = elements.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                   elements.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ||
                   elements.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    if (elements.type != TINYGLTF_TYPE_SCALAR || !integer) throw Error(file, place, "indices must be unsigned integer scalars");
    std::vector<uint32_t> indices(elements.count);
    for (size_t i = 0; i < elements.count; ++i)
        indices[i] = uint32_t(component(elements.first + i * elements.stride, elements.componentType, false));
    return indices;
}

struct MeshBuilder {
    const tinygltf::Model& model;
    const std::string& file;
    TriMesh mesh;
    SceneAsset* scene = nullptr; // when set: a receiver per primitive, texcoord sets, colours, material rule below
    bool allNormals = true;
    bool allTexcoords = true;
    bool anyAlbedo = false;
    bool anyTexcoords[2] = {false, false};
    bool anyColor = false;
    size_t skippedPrimitives = 0;
    uint64_t primitiveInstances = 0;
};

// glTF instancing (one mesh under many nodes) multiplies what a small file expands to: this many primitive
// instances at most, besides the element cap on the vertices they add up to.
constexpr uint64_t kMaxPrimitiveInstances = 1u << 20;
constexpr size_t kMaxNodes = 1u << 20;

// Triangle-list corners of a TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN primitive's `corners`, by the glTF 2.0
// rule for each mode (strips alternate winding so every triangle keeps the first one's). Strip and fan
// triangles that repeat a corner (the usual way of joining strips) are dropped.
std::vector<uint32_t> triangleList(int mode, const std::vector<uint32_t>& corners, const std::string& file,
                                   const std::string& place) {
    if (mode == TINYGLTF_MODE_TRIANGLES || mode == -1) {
        if (corners.size() % 3 != 0) throw Error(file, place, "index count is not a multiple of 3");
        return corners;
    }
    std::vector<uint32_t> list;
    if (corners.size() < 3) return list;
    list.reserve(3 * (corners.size() - 2));
    for (size_t i = 0; i + 2 < corners.size(); ++i) {
        uint32_t a, b, c;
        if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            a = corners[i];
            b = corners[i + 1 + i % 2];
            c = corners[i + 2 - i % 2];
        } else {
            a = corners[i + 1];
            b = corners[i + 2];
            c = corners[0];
        }
        if (a == b || b == c || a == c) continue;
        list.insert(list.end(), {a, b, c});
    }
    return list;
}

void transformPoints(std::vector<float>& xyz, size_t first, const Matrix& m) {
    for (size_t i = first; i < xyz.size(); i += 3) {
        double x = xyz[i], y = xyz[i + 1], z = xyz[i + 2];
        for (int row = 0; row < 3; ++row) xyz[i + row] = float(m[row] * x + m[4 + row] * y + m[8 + row] * z + m[12 + row]);
    }
}

// Normals transform by the inverse transpose of the linear part: its cofactor matrix, whose columns are cross
// products of the linear part's columns, times the sign of its determinant (the length is renormalized).
void transformNormals(std::vector<float>& xyz, size_t first, const Matrix& m, double determinantSign) {
    auto column = [&](int c) { return std::array<double, 3>{m[c * 4], m[c * 4 + 1], m[c * 4 + 2]}; };
    auto cross = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
        return std::array<double, 3>{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    };
    std::array<double, 3> a0 = column(0), a1 = column(1), a2 = column(2);
    std::array<std::array<double, 3>, 3> cofactor = {cross(a1, a2), cross(a2, a0), cross(a0, a1)};
    for (size_t i = first; i < xyz.size(); i += 3) {
        double n[3] = {0, 0, 0};
        for (int c = 0; c < 3; ++c)
            for (int row = 0; row < 3; ++row) n[row] += determinantSign * cofactor[c][row] * xyz[i + c];
        double length = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (length > 0)
            for (int row = 0; row < 3; ++row) xyz[i + row] = float(n[row] / length);
    }
}

double linearDeterminant(const Matrix& m) {
    return m[0] * (m[5] * m[10] - m[6] * m[9]) - m[4] * (m[1] * m[10] - m[2] * m[9]) + m[8] * (m[1] * m[6] - m[2] * m[5]);
}

void addPrimitive(MeshBuilder& builder, const tinygltf::Primitive& primitive, const Matrix& world, const std::string& place) {
    if (primitive.mode != TINYGLTF_MODE_TRIANGLES && primitive.mode != -1 && primitive.mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        primitive.mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        ++builder.skippedPrimitives;
        return;
    }
    if (++builder.primitiveInstances > kMaxPrimitiveInstances)
        throw Error(builder.file, place, "more than " + std::to_string(kMaxPrimitiveInstances) +
                                             " primitive instances (nodes times primitives); prt refuses larger scenes");
    TriMesh& mesh = builder.mesh;
    const tinygltf::Model& model = builder.model;
    auto attribute = [&](const char* name) {
        auto found = primitive.attributes.find(name);
        return found == primitive.attributes.end() ? -1 : found->second;
    };
    if (attribute("POSITION") < 0) throw Error(builder.file, place, "primitive has no POSITION");
    size_t base = mesh.vertexCount();
    {
        int position = attribute("POSITION");
        uint64_t claimed = position >= 0 && size_t(position) < model.accessors.size() ? model.accessors[position].count : 0;
        checkElementCount(uint64_t(base) + claimed, "vertices", builder.file, place + ".POSITION");
    }
    size_t count = appendFloats(model, attribute("POSITION"), 3, mesh.positions, builder.file, place + ".POSITION");

    bool identity = world == kIdentity;
    double determinant = linearDeterminant(world);
    if (!identity) transformPoints(mesh.positions, base * 3, world);

    builder.allNormals = builder.allNormals && attribute("NORMAL") >= 0;
    if (builder.allNormals) {
        size_t normalCount = appendFloats(model, attribute("NORMAL"), 3, mesh.normals, builder.file, place + ".NORMAL");
        if (normalCount != count) throw Error(builder.file, place + ".NORMAL", "count differs from POSITION's");
        if (!identity) transformNormals(mesh.normals, base * 3, world, determinant < 0 ? -1.0 : 1.0);
    }
    builder.allTexcoords = builder.allTexcoords && attribute("TEXCOORD_0") >= 0;
    if (builder.allTexcoords &&
        appendFloats(model, attribute("TEXCOORD_0"), 2, mesh.texcoords, builder.file, place + ".TEXCOORD_0") != count)
        throw Error(builder.file, place + ".TEXCOORD_0", "count differs from POSITION's");

    // Albedo is gathered for every primitive and dropped at the end if it is 1 everywhere. A scene takes the
    // material's diffuse albedo, base colour times (1 - metallic) (asset.h); a merged mesh its base colour alone.
    std::array<double, 3> factor = {1.0, 1.0, 1.0};
    if (primitive.material >= 0 && size_t(primitive.material) >= model.materials.size())
        throw Error(builder.file, place + ".material", "material " + std::to_string(primitive.material) + " does not exist");
    if (builder.scene) {
        const MaterialRecord& material =
            builder.scene->materials[primitive.material >= 0 ? size_t(primitive.material) : builder.scene->materials.size() - 1];
        for (int c = 0; c < 3; ++c) factor[c] = double(material.baseColorFactor[c]) * (1.0 - double(material.metallic));
    } else if (primitive.material >= 0) {
        const std::vector<double>& baseColor = model.materials[primitive.material].pbrMetallicRoughness.baseColorFactor;
        if (baseColor.size() >= 3) factor = {baseColor[0], baseColor[1], baseColor[2]};
    }
    if (attribute("COLOR_0") >= 0) {
        std::vector<float> rgba;
        size_t colorCount = appendColors(model, attribute("COLOR_0"), rgba, builder.file, place + ".COLOR_0");
        if (colorCount != count) throw Error(builder.file, place + ".COLOR_0", "count differs from POSITION's");
        for (size_t i = 0; i < count; ++i)
            for (int c = 0; c < 3; ++c) mesh.albedo.push_back(float(rgba[4 * i + c] * factor[c]));
        builder.anyAlbedo = true;
        if (builder.scene) {
            std::vector<float>& colors = builder.scene->colors;
            colors.resize(4 * base, 1.0f); // primitives before without COLOR_0
            colors.insert(colors.end(), rgba.begin(), rgba.end());
            builder.anyColor = true;
        }
    } else {
        for (size_t i = 0; i < count; ++i) mesh.albedo.insert(mesh.albedo.end(), {float(factor[0]), float(factor[1]), float(factor[2])});
        builder.anyAlbedo = builder.anyAlbedo || factor != std::array<double, 3>{1.0, 1.0, 1.0};
    }
    if (builder.scene) {
        for (int set = 0; set < 2; ++set) {
            const char* name = set == 0 ? "TEXCOORD_0" : "TEXCOORD_1";
            std::vector<float>& uv = builder.scene->texcoords[set];
            uv.resize(2 * base, 0.0f);
            if (attribute(name) >= 0) {
                if (appendFloats(model, attribute(name), 2, uv, builder.file, place + "." + name) != count)
                    throw Error(builder.file, place + "." + name, "count differs from POSITION's");
                builder.anyTexcoords[set] = true;
            } else {
                uv.resize(2 * (base + count), 0.0f);
            }
        }
    }

    std::vector<uint32_t> indices;
    if (primitive.indices >= 0) {
        indices = readIndices(model, primitive.indices, builder.file, place + ".indices");
    } else {
        indices.resize(count);
        for (size_t i = 0; i < count; ++i) indices[i] = uint32_t(i);
    }
    indices = triangleList(primitive.mode, indices, builder.file, place);
    for (uint32_t& index : indices) index = index < count ? uint32_t(base + index) : std::numeric_limits<uint32_t>::max();
    // A mirroring transform turns counter-clockwise triangles clockwise.
    if (determinant < 0)
        for (size_t t = 0; t < indices.size(); t += 3) std::swap(indices[t + 1], indices[t + 2]);
    if (builder.scene) {
        SceneAsset& scene = *builder.scene;
        SceneReceiver receiver;
        receiver.material = primitive.material >= 0 ? primitive.material : int(scene.materials.size()) - 1;
        receiver.firstVertex = uint32_t(base);
        receiver.vertexCount = uint32_t(count);
        receiver.firstTriangle = uint32_t(mesh.indices.size() / 3);
        receiver.triangleCount = uint32_t(indices.size() / 3);
        receiver.world = world;
        receiver.mirrored = determinant < 0;
        scene.triangleReceiver.resize(scene.triangleReceiver.size() + receiver.triangleCount, uint32_t(scene.receivers.size()));
        scene.receivers.push_back(receiver); // node, mesh and primitive are set by the caller
    }
    mesh.indices.insert(mesh.indices.end(), indices.begin(), indices.end());
}

void addMesh(MeshBuilder& builder, int meshIndex, const Matrix& world, const std::string& place, int node = -1) {
    if (meshIndex < 0 || size_t(meshIndex) >= builder.model.meshes.size())
        throw Error(builder.file, place, "mesh " + std::to_string(meshIndex) + " does not exist");
    const tinygltf::Mesh& mesh = builder.model.meshes[meshIndex];
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        size_t receivers = builder.scene ? builder.scene->receivers.size() : 0;
        addPrimitive(builder, mesh.primitives[p], world,
                     "meshes[" + std::to_string(meshIndex) + "].primitives[" + std::to_string(p) + "]");
        if (builder.scene && builder.scene->receivers.size() > receivers) {
            SceneReceiver& receiver = builder.scene->receivers.back();
            receiver.node = node;
            receiver.mesh = meshIndex;
            receiver.primitive = int(p);
        }
    }
}

// The node forest of `sceneIndex`, walked without recursion. glTF requires a forest: no node has two parents
// (which includes being listed twice by one), scene roots have none and nothing is its own ancestor. A file that
// breaks the rule is refused up front, so a tiny DAG can never expand exponentially.
void addScene(MeshBuilder& builder, int sceneIndex) {
    const tinygltf::Model& model = builder.model;
    const size_t nodeCount = model.nodes.size();
    auto nodePlace = [](size_t n) { return "nodes[" + std::to_string(n) + "]"; };
    std::vector<int> parent(nodeCount, -1);
    for (size_t n = 0; n < nodeCount; ++n)
        for (int child : model.nodes[n].children) {
            if (child < 0 || size_t(child) >= nodeCount)
                throw Error(builder.file, nodePlace(n) + ".children", "node " + std::to_string(child) + " does not exist");
            if (parent[child] >= 0)
                throw Error(builder.file, nodePlace(n) + ".children",
                            "node " + std::to_string(child) + " already has parent " + std::to_string(parent[child]) +
                                "; glTF nodes have at most one parent");
            parent[child] = int(n);
        }
    struct Pending {
        int node;
        Matrix parentWorld;
    };
    std::vector<char> visited(nodeCount, 0);
    std::vector<Pending> stack;
    const std::string scenePlace = "scenes[" + std::to_string(sceneIndex) + "].nodes";
    const std::vector<int>& roots = model.scenes[sceneIndex].nodes;
    for (auto root = roots.rbegin(); root != roots.rend(); ++root) {
        if (*root < 0 || size_t(*root) >= nodeCount)
            throw Error(builder.file, scenePlace, "node " + std::to_string(*root) + " does not exist");
        if (parent[*root] >= 0)
            throw Error(builder.file, scenePlace, "node " + std::to_string(*root) + " is a root but has parent " +
                                                      std::to_string(parent[*root]));
        stack.push_back({*root, kIdentity});
    }
    while (!stack.empty()) {
        Pending item = stack.back();
        stack.pop_back();
        // Single parents and parent-free roots leave only a repeated root or a cycle to revisit a node.
        if (visited[item.node])
            throw Error(builder.file, nodePlace(size_t(item.node)), "is reached twice (listed twice as a root, or its own ancestor)");
        visited[item.node] = 1;
        const tinygltf::Node& node = model.nodes[item.node];
        Matrix world = multiply(item.parentWorld, localMatrix(node));
        if (node.mesh >= 0) addMesh(builder, node.mesh, world, nodePlace(size_t(item.node)), item.node);
        for (auto child = node.children.rbegin(); child != node.children.rend(); ++child) stack.push_back({*child, world});
    }
    for (size_t n = 0; n < nodeCount; ++n)
        if (!visited[n] && parent[n] >= 0) {
            // A cycle that no root reaches: harmless to the mesh, but the file is not a valid node forest.
            size_t top = n;
            std::vector<char> seen(nodeCount, 0);
            while (parent[top] >= 0 && !seen[top]) {
                seen[top] = 1;
                top = size_t(parent[top]);
            }
            if (parent[top] >= 0) throw Error(builder.file, nodePlace(top), "is its own ancestor");
        }
}

} // namespace

// What every reader does once the primitives are gathered: drop arrays not every primitive had, refuse no triangles.
static TriMesh finishMesh(MeshBuilder& builder, const std::string& noTriangles) {
    if (builder.skippedPrimitives > 0)
        logWarn(builder.file + ": skipped primitives that are points or lines: " + std::to_string(builder.skippedPrimitives));
    TriMesh& mesh = builder.mesh;
    if (mesh.indices.empty()) throw Error(builder.file, "", noTriangles);
    if (!builder.allNormals) mesh.normals.clear();
    if (!builder.allTexcoords) mesh.texcoords.clear();
    if (!builder.anyAlbedo) mesh.albedo.clear();
    return std::move(mesh);
}

void requireGltf2(const std::string& version, const std::string& file) {
    if (!version.empty() && version[0] == '1')
        throw Error(file, "asset.version", "glTF " + version.substr(0, 20) + " is not supported; prt reads glTF 2.0 "
                                           "(convert the file, for example with the Khronos glTF 1.0 to 2.0 converter)");
}

// Walks the default scene (every mesh once, untransformed, when the file has no scene) into the builder.
static void addDefaultScene(MeshBuilder& builder) {
    const tinygltf::Model& model = builder.model;
    requireGltf2(model.asset.version, builder.file);
    if (model.nodes.size() > kMaxNodes)
        throw Error(builder.file, "nodes", std::to_string(model.nodes.size()) + " nodes, more than the " +
                                               std::to_string(kMaxNodes) + " prt reads");
    if (model.scenes.empty()) {
        for (size_t m = 0; m < model.meshes.size(); ++m) addMesh(builder, int(m), kIdentity, "meshes");
    } else {
        int sceneIndex = model.defaultScene >= 0 && size_t(model.defaultScene) < model.scenes.size() ? model.defaultScene : 0;
        addScene(builder, sceneIndex);
    }
}

static const char* kNoSceneTriangles =
    "no triangles: no TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN primitive is reachable from the scene";

TriMesh readGltfMesh(const tinygltf::Model& model, const std::string& file) {
    MeshBuilder builder{model, file, TriMesh{}};
    addDefaultScene(builder);
    return finishMesh(builder, kNoSceneTriangles);
}

TriMesh readGltfScene(const tinygltf::Model& model, const std::string& file, SceneAsset& scene) {
    readMaterials(model, file, scene);
    MeshBuilder builder{model, file, TriMesh{}, &scene};
    addDefaultScene(builder);
    TriMesh mesh = finishMesh(builder, kNoSceneTriangles);
    const size_t vertices = mesh.vertexCount();
    for (int set = 0; set < 2; ++set)
        if (!builder.anyTexcoords[set]) scene.texcoords[set].clear();
    if (builder.anyColor) scene.colors.resize(4 * vertices, 1.0f);
    else scene.colors.clear();
    return mesh;
}

TriMesh readGltfPrimitive(const tinygltf::Model& model, int meshIndex, int primitiveIndex, const std::string& file) {
    const std::string place = "meshes[" + std::to_string(meshIndex) + "].primitives[" + std::to_string(primitiveIndex) + "]";
    if (meshIndex < 0 || size_t(meshIndex) >= model.meshes.size() || primitiveIndex < 0 ||
        size_t(primitiveIndex) >= model.meshes[size_t(meshIndex)].primitives.size())
        throw Error(file, place, "does not exist");
    MeshBuilder builder{model, file, TriMesh{}};
    addPrimitive(builder, model.meshes[size_t(meshIndex)].primitives[size_t(primitiveIndex)], kIdentity, place);
    return std::move(builder.mesh);
}

TriMesh readGltfMeshAt(const tinygltf::Model& model, int meshIndex, const std::string& file) {
    requireGltf2(model.asset.version, file);
    MeshBuilder builder{model, file, TriMesh{}};
    addMesh(builder, meshIndex, kIdentity, "meshes");
    return finishMesh(builder, "no triangles in meshes[" + std::to_string(meshIndex) + "]");
}

} // namespace prt::detail
