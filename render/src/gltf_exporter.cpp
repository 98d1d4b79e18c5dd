// `--export glb`: the whole animation as one binary glTF 2.0 file (export/animation.glb), written
// with tinygltf (Debian libtinygltf-dev).
//
// Encoding (glTF 2.0 §3.7.2.2 "Morph Targets", §3.11 "Animations"): every object is a node with one
// mesh whose POSITION is its rest surface (world coordinates, m, the vertices of export/NAME.obj in
// their order) and one morph target per output frame of the range, the frame's displacement from
// the rest surface. One animation drives the nodes' morph weights: at t_k = k / fps the weight of
// target k is 1 and every other is 0, with LINEAR interpolation, so that between two frames the
// surface moves linearly, as squeeze's own frames do. Each object gets a material whose base colour
// is its render colour (double-sided: open surfaces show both sides). glTF is +Y up, metres, like
// squeeze's scenes; importers convert to their own axes (Blender: +Z up).
#include <spdlog/spdlog.h>

#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/render/export_formats.h"

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

namespace squeeze::render {
namespace fs = std::filesystem;

namespace {

// Appends `bytes` to buffer 0 of `m` (4-byte aligned) as a new buffer view; returns its index.
int add_view(tinygltf::Model& m, const void* bytes, size_t size, int target) {
  std::vector<unsigned char>& data = m.buffers[0].data;
  while (data.size() % 4) data.push_back(0);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = data.size();
  view.byteLength = size;
  if (target) view.target = target;
  const auto* p = static_cast<const unsigned char*>(bytes);
  data.insert(data.end(), p, p + size);
  m.bufferViews.push_back(view);
  return static_cast<int>(m.bufferViews.size()) - 1;
}

// A float accessor of `count` elements of `type` over a new buffer view of `values`; with_bounds
// sets min/max (required for POSITION and animation inputs).
int add_float_accessor(tinygltf::Model& m, const std::vector<float>& values, int type, size_t count, bool with_bounds,
                       int target = 0) {
  tinygltf::Accessor a;
  a.bufferView = add_view(m, values.data(), values.size() * sizeof(float), target);
  a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  a.type = type;
  a.count = count;
  if (with_bounds) {
    const size_t n = values.size() / std::max<size_t>(count, 1);
    a.minValues.assign(n, std::numeric_limits<double>::infinity());
    a.maxValues.assign(n, -std::numeric_limits<double>::infinity());
    for (size_t i = 0; i < values.size(); ++i) {
      a.minValues[i % n] = std::min<double>(a.minValues[i % n], values[i]);
      a.maxValues[i % n] = std::max<double>(a.maxValues[i % n], values[i]);
    }
  }
  m.accessors.push_back(a);
  return static_cast<int>(m.accessors.size()) - 1;
}

class GltfExporter final : public Exporter {
 public:
  void begin(const ExportContext& c) override {
    context_ = c;
    frames_.assign(c.objects.size(), {});
    for (const ExportObject& ob : c.objects)
      if (ob.rest.rows() > std::numeric_limits<std::uint32_t>::max())
        throw InputError((c.folder / "animation.glb").string() + ": object '" + ob.name + "' has too many vertices for glTF");
    const double bytes = [&] {
      double b = 0;
      for (const ExportObject& ob : c.objects) b += 12.0 * static_cast<double>(ob.rest.rows()) * c.frame_count;
      return b;
    }();
    if (bytes > 2e9)  // the GLB container's length field is 32-bit (glTF 2.0 §4.4.2)
      throw InputError((c.folder / "animation.glb").string() + ": " + std::to_string(static_cast<long long>(bytes / 1e6)) +
                       " MB of morph targets exceed a GLB file's 2 GB (render fewer frames with --frames)");
  }

  void frame(int, double, const std::vector<ExportState>& states) override {
    for (size_t b = 0; b < states.size(); ++b) {
      const ExportObject& ob = context_.objects[b];
      std::vector<float>& d = frames_[b].emplace_back(static_cast<size_t>(ob.rest.rows()) * 3);
      for (Eigen::Index v = 0; v < ob.rest.rows(); ++v)
        for (int k = 0; k < 3; ++k)
          d[static_cast<size_t>(v * 3 + k)] = static_cast<float>(states[b].surface(v, k) - ob.rest(v, k));
    }
  }

  void finish() override {
    tinygltf::Model m;
    m.asset.version = "2.0";
    m.asset.generator = "squeeze";
    m.buffers.emplace_back();
    m.scenes.emplace_back();
    m.defaultScene = 0;
    const int frames = context_.frame_count;

    // The animation's input: the frames' times, shared by every channel.
    std::vector<float> times(static_cast<size_t>(frames));
    for (int i = 0; i < frames; ++i) times[static_cast<size_t>(i)] = static_cast<float>((context_.first_frame + i) / context_.fps);
    const int time_accessor = add_float_accessor(m, times, TINYGLTF_TYPE_SCALAR, times.size(), true);
    // Its output: frames × frames weights, one-hot (target i at time i); the same for every object.
    std::vector<float> weights(static_cast<size_t>(frames) * frames, 0.0f);
    for (int i = 0; i < frames; ++i) weights[static_cast<size_t>(i) * frames + i] = 1.0f;
    const int weight_accessor = add_float_accessor(m, weights, TINYGLTF_TYPE_SCALAR, weights.size(), false);
    tinygltf::Animation animation;
    animation.name = "squeeze";

    for (size_t b = 0; b < context_.objects.size(); ++b) {
      const ExportObject& ob = context_.objects[b];
      tinygltf::Material material;
      material.name = ob.name;
      material.pbrMetallicRoughness.baseColorFactor = {ob.colour.x(), ob.colour.y(), ob.colour.z(), 1.0};
      material.pbrMetallicRoughness.metallicFactor = 0.0;
      material.pbrMetallicRoughness.roughnessFactor = ob.rigid ? 0.6 : 0.45;
      material.doubleSided = true;
      m.materials.push_back(material);

      std::vector<float> rest(static_cast<size_t>(ob.rest.rows()) * 3);
      for (Eigen::Index v = 0; v < ob.rest.rows(); ++v)
        for (int k = 0; k < 3; ++k) rest[static_cast<size_t>(v * 3 + k)] = static_cast<float>(ob.rest(v, k));
      std::vector<std::uint32_t> indices(static_cast<size_t>(ob.faces.size()));
      for (Eigen::Index f = 0; f < ob.faces.rows(); ++f)
        for (int k = 0; k < 3; ++k) indices[static_cast<size_t>(f * 3 + k)] = static_cast<std::uint32_t>(ob.faces(f, k));

      tinygltf::Primitive prim;
      prim.mode = TINYGLTF_MODE_TRIANGLES;
      prim.material = static_cast<int>(m.materials.size()) - 1;
      prim.attributes["POSITION"] =
          add_float_accessor(m, rest, TINYGLTF_TYPE_VEC3, static_cast<size_t>(ob.rest.rows()), true, TINYGLTF_TARGET_ARRAY_BUFFER);
      tinygltf::Accessor ia;
      ia.bufferView = add_view(m, indices.data(), indices.size() * 4, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
      ia.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
      ia.type = TINYGLTF_TYPE_SCALAR;
      ia.count = indices.size();
      m.accessors.push_back(ia);
      prim.indices = static_cast<int>(m.accessors.size()) - 1;
      tinygltf::Value::Array target_names;
      for (int i = 0; i < frames; ++i) {
        const int a = add_float_accessor(m, frames_[b][static_cast<size_t>(i)], TINYGLTF_TYPE_VEC3,
                                         static_cast<size_t>(ob.rest.rows()), true, TINYGLTF_TARGET_ARRAY_BUFFER);
        prim.targets.push_back({{"POSITION", a}});
        target_names.emplace_back(frame_file_name("frame_", context_.first_frame + i, ""));
      }
      frames_[b].clear();
      frames_[b].shrink_to_fit();

      tinygltf::Mesh mesh;
      mesh.name = ob.name;
      mesh.primitives.push_back(prim);
      mesh.weights.assign(static_cast<size_t>(frames), 0.0);
      mesh.weights[0] = 1.0;
      tinygltf::Value::Object extras;
      extras["targetNames"] = tinygltf::Value(target_names);  // the names importers give the targets
      mesh.extras = tinygltf::Value(extras);
      m.meshes.push_back(mesh);

      tinygltf::Node node;
      node.name = ob.name;
      node.mesh = static_cast<int>(m.meshes.size()) - 1;
      m.nodes.push_back(node);
      const int node_index = static_cast<int>(m.nodes.size()) - 1;
      m.scenes[0].nodes.push_back(node_index);

      tinygltf::AnimationSampler sampler;
      sampler.input = time_accessor;
      sampler.output = weight_accessor;
      sampler.interpolation = "LINEAR";
      animation.samplers.push_back(sampler);
      tinygltf::AnimationChannel channel;
      channel.sampler = static_cast<int>(animation.samplers.size()) - 1;
      channel.target_node = node_index;
      channel.target_path = "weights";
      animation.channels.push_back(channel);
    }
    m.animations.push_back(animation);
    m.buffers[0].data.resize((m.buffers[0].data.size() + 3) / 4 * 4, 0);

    const fs::path target = context_.folder / "animation.glb";
    write_atomically(target, [&](const fs::path& tmp) {
      std::ofstream out(tmp, std::ios::binary);
      if (!out) throw InputError(target.string() + ": cannot open for writing");
      tinygltf::TinyGLTF writer;
      if (!writer.WriteGltfSceneToStream(&m, out, false, true) || !out.flush())
        throw InputError(target.string() + ": write failed (disk full?)");
    });
    spdlog::debug("glb: {} objects, {} frames, {:.1f} MB", context_.objects.size(), frames,
                  m.buffers[0].data.size() / 1e6);
  }

 private:
  ExportContext context_;
  std::vector<std::vector<std::vector<float>>> frames_;  // per object and frame: displacements (x, y, z per vertex)
};

}  // namespace

ExportFormat glb_export_format() {
  return {"glb", "the whole animation as one glTF 2.0 binary: a mesh per object, its motion as morph targets",
          [] { return std::make_unique<GltfExporter>(); }};
}

}  // namespace squeeze::render
