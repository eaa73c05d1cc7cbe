// foveal/scene/mesh_loader.cpp — meshes through Assimp (OBJ+MTL, PLY, glTF, …) and their textures.
#include "foveal/scene/scene.h"
#include "foveal/util/error.h"
#include "foveal/util/files.h"
#include "foveal/util/image_file.h"
#include "foveal/util/text.h"

#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/core.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string_view>
#include <map>

namespace foveal {
namespace {

// Load a texture once per scene; a missing or unreadable texture is a warning, not an error.
int load_texture(Scene& scene, std::map<std::string, int>& cache, const std::filesystem::path& file) {
  const std::string key = file.lexically_normal().string();
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  // The same checks as every image foveal reads: OpenCV decodes by the content, and content of
  // another format (DICOM under a .jpg name) reaches decoders that abort the process
  cv::Mat image;
  std::string why = "unknown or corrupt format";
  try {
    check_image_file(key);
    note_input(key);
    image = cv::imread(key, cv::IMREAD_COLOR);
  } catch (const Error& e) {
    why = e.what();
  } catch (const cv::Exception& e) {
    why = e.err;
  }
  if (image.empty()) {
    fmt::print(stderr, "foveal: warning: texture '{}' could not be read ({}); using the material colour\n", key, why);
    return cache[key] = -1;
  }
  cv::cvtColor(image, image, cv::COLOR_BGR2RGB);
  Texture tex;
  tex.path = key;
  tex.width = image.cols;
  tex.height = image.rows;
  tex.rgb.assign(image.data, image.data + image.total() * 3);
  scene.textures.push_back(std::move(tex));
  return cache[key] = static_cast<int>(scene.textures.size() - 1);
}

// A PLY file is checked before Assimp 5.2 reads it, where its reader fails on malformed files
// (found by mutating small PLY files):
// - a header without an "end_header" line (cut short, the marker run into the data, the file
//   ending at it) made it loop for ever;
// - a list length no face has (a corrupt binary count of 0x30000000 in a 330-byte file) made it
//   allocate 20 GB before saying "File corrupted", and an element count beyond what the file holds
//   made it allocate first too.
// So the header is read (up to 1 MiB: PLY headers are a few hundred bytes), and the data walked:
// each list's length at most 32767, the most corners Assimp keeps per face, and each element's
// count within the bytes left. Data that ends early is left to Assimp to judge.
struct PlyProperty {
  int size = 0;        // bytes of a value (binary)
  int count_size = 0;  // bytes of a list's length; 0: not a list
  bool signed_count = false;
};
struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

int ply_type_size(std::string_view type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "int32" || type == "uint32" || type == "float" || type == "float32") return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

constexpr uint64_t kMaxPlyListLength = 32767;  // Assimp's AI_MAX_FACE_INDICES

void check_ply(const std::string& path) {
  const std::string text = text::read_file(path, size_t(1) << 34);
  const std::string_view head = std::string_view(text).substr(0, size_t(1) << 20);
  if (!head.starts_with("ply\n") && !head.starts_with("ply\r\n")) fail("{}: not a PLY file (it does not start with a line 'ply')", path);
  std::vector<PlyElement> elements;
  enum class Format { ascii, little, big, other } format = Format::other;
  size_t body = std::string::npos, line = 1;
  bool walkable = true;  // every property's type known
  for (size_t at = 0; at < head.size(); ++line) {
    const size_t end = head.find('\n', at);
    if (end == std::string_view::npos) break;  // the last line has no end: not a whole header line
    const auto f = text::split(text::trim(head.substr(at, end - at)), ' ');
    at = end + 1;
    if (f.empty()) continue;
    if (f[0] == "end_header" && f.size() == 1) {
      body = at;
      break;
    }
    if (f[0] == "format" && f.size() >= 2)
      format = f[1] == "ascii"                  ? Format::ascii
               : f[1] == "binary_little_endian" ? Format::little
               : f[1] == "binary_big_endian"    ? Format::big
                                                : Format::other;
    if (f[0] == "element" && f.size() >= 3) {
      const auto count = text::to_number(f[2]);
      // (a count beyond 1e18 is held as 1e18: no file holds that many, and the walk says so)
      elements.push_back({std::string(f[1]), count && *count >= 0 ? uint64_t(std::min(*count, 1e18)) : 0, {}});
    }
    if (f[0] == "property" && !elements.empty()) {
      PlyProperty p;
      if (f.size() >= 5 && f[1] == "list") {
        p.count_size = ply_type_size(f[2]);
        p.signed_count = f[2] == "char" || f[2] == "short" || f[2] == "int" || f[2] == "int8" || f[2] == "int16" || f[2] == "int32";
        p.size = ply_type_size(f[3]);
        walkable = walkable && p.count_size != 0 && p.size != 0;  // else a type Assimp will name
      } else if (f.size() >= 3) {
        walkable = walkable && (p.size = ply_type_size(f[1])) != 0;
      } else {
        walkable = false;
      }
      elements.back().properties.push_back(p);
    }
  }
  if (body == std::string::npos)
    fail("{}: a PLY header without an 'end_header' line (read {} lines): the file is cut short or is not a PLY file", path, line - 1);
  if (format == Format::other || !walkable) return;  // Assimp says what is wrong with the format or a type
  const std::string_view data = std::string_view(text).substr(body);
  size_t at = 0;
  auto too_long = [&](const PlyElement& e, uint64_t i, double length) {
    fail("{}: {} {} of {} holds a list of {} values (a face has at most {} corners): the file is corrupt", path, e.name, i, e.count, length,
         kMaxPlyListLength);
  };
  auto token = [&]() {  // the next whitespace-separated value of an ASCII file; empty at its end
    while (at < data.size() && std::isspace(static_cast<unsigned char>(data[at]))) ++at;
    const size_t start = at;
    while (at < data.size() && !std::isspace(static_cast<unsigned char>(data[at]))) ++at;
    return data.substr(start, at - start);
  };
  for (const PlyElement& e : elements) {
    // Each instance takes at least a byte per value (binary) or two (a digit and a space)
    uint64_t least = 0;
    for (const PlyProperty& p : e.properties) least += format == Format::ascii ? 2 : uint64_t(p.count_size ? p.count_size : p.size);
    const size_t left = data.size() - std::min(at, data.size()) + (format == Format::ascii ? 1 : 0);  // (the last value may end the file)
    if (least > 0 && e.count > left / least)
      fail("{}: element '{}' claims {} instances, more than the {} bytes left in the file hold: the file is cut short or corrupt", path,
           e.name, e.count, data.size() - std::min(at, data.size()));
    if (e.properties.empty()) continue;  // nothing to walk (and a count that holds no bytes)
    for (uint64_t i = 0; i < e.count; ++i)
      for (const PlyProperty& p : e.properties) {
        if (format == Format::ascii) {
          const std::string_view value = token();
          if (value.empty()) return;  // data ends early: Assimp judges
          if (p.count_size == 0) continue;
          const auto length = text::to_number(value);
          if (!length) return;
          if (*length < 0 || *length > double(kMaxPlyListLength)) too_long(e, i, *length);
          for (int k = 0; k < static_cast<int>(*length); ++k)
            if (token().empty()) return;
        } else {
          if (p.count_size == 0) {
            at += static_cast<size_t>(p.size);
            continue;
          }
          if (at + static_cast<size_t>(p.count_size) > data.size()) return;
          uint64_t length = 0;
          for (int k = 0; k < p.count_size; ++k) {
            const auto byte = static_cast<unsigned char>(data[at + static_cast<size_t>(format == Format::big ? k : p.count_size - 1 - k)]);
            length = length << 8 | byte;
          }
          at += static_cast<size_t>(p.count_size);
          const bool negative = p.signed_count && (length >> (8 * p.count_size - 1)) != 0;
          if (negative || length > kMaxPlyListLength)
            too_long(e, i, negative ? double(length) - std::ldexp(1.0, 8 * p.count_size) : double(length));
          at += static_cast<size_t>(length) * static_cast<size_t>(p.size);
        }
        if (at > data.size()) return;
      }
  }
}

// The files Assimp opens, checked first where its readers crash on malformed ones: a material
// library (.mtl) with a statement before any "newmtl" line makes Assimp 5.2's MTL reader write to
// a material that does not exist (a segmentation fault; found by mutating MTL files). Such a file
// is not opened, and the problem, kept here, becomes the error once Assimp returns.
class CheckedFiles : public Assimp::DefaultIOSystem {
 public:
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    // Every file a mesh is read from (the mesh, its .mtl, a glTF's buffers) is an input of the run
    if (mode != nullptr && mode[0] == 'r' && Exists(file)) note_input(file);
    if (lower_extension(file) == ".mtl" && Exists(file)) {  // (Assimp may open it more than once)
      try {
        check_material_library(file);
      } catch (const Error& e) {
        if (problem.empty()) problem = e.what();
        return nullptr;
      }
    }
    return DefaultIOSystem::Open(file, mode);
  }
  std::string problem;

 private:
  static void check_material_library(const std::string& path) {
    const std::string text = text::read_file(path);
    text::Lines lines(text::strip_bom(text));
    std::string_view line;
    while (lines.next(line)) {
      const auto fields = text::split(text::trim(line), ' ');
      if (fields.empty() || fields[0].empty() || fields[0][0] == '#') continue;
      if (fields[0] != "newmtl")
        fail("{}:{}: '{}' before any 'newmtl' line (a material library starts each material with 'newmtl NAME')", path, lines.number(),
             text::printable(fields[0]));
      return;
    }
  }
};

glm::vec3 colour(const aiMaterial* m, const char* key, unsigned type, unsigned index, glm::vec3 fallback) {
  aiColor3D c;
  if (m->Get(key, type, index, c) != AI_SUCCESS) return fallback;
  return {c.r, c.g, c.b};
}

}  // namespace

void append_mesh_file(Scene& scene, const std::string& path, const glm::mat4& transform, std::optional<glm::vec3> diffuse_override) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) fail("{}: no such file", path);
  if (fs::file_size(path, ec) == 0) fail("{}: file is empty", path);
  const std::string ext = lower_extension(path);
  {
    // Assimp picks a reader by the extension, and by the content where the extension is not its
    std::ifstream in(path, std::ios::binary);
    char magic[4] = {};
    in.read(magic, 4);
    if (ext == ".ply" || (std::string_view(magic, 3) == "ply" && (magic[3] == '\n' || magic[3] == '\r'))) check_ply(path);
  }
  // Triangulate, bake node transforms, drop points and lines; append_mesh fills in missing normals
  Assimp::Importer importer;
  auto* files = new CheckedFiles;  // the importer owns it
  importer.SetIOHandler(files);
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // PLY is indexed already: joining identical vertices there only costs memory and time (about
  // a third of the peak on a 2-million-triangle scan); formats that store vertices per face need it
  const unsigned join = ext == ".ply" ? 0u : unsigned(aiProcess_JoinIdenticalVertices);
  // Read and validated first; then each mesh's faces are checked, and its primitive types set from
  // them, before the steps that rely on them: Assimp 5.2's PLY reader gives a malformed binary
  // file faces of no corners, labelled polygons, and triangulating them fails an assertion that
  // aborts the process (found by mutating PLY files)
  const aiScene* ai = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  if (!files->problem.empty()) fail("{}", files->problem);
  if (ai == nullptr) fail("{}: cannot read mesh: {}", path, importer.GetErrorString());
  for (unsigned mi = 0; mi < ai->mNumMeshes; ++mi) {
    aiMesh* mesh = ai->mMeshes[mi];  // (the scene's meshes are the importer's, not const)
    unsigned types = 0;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const unsigned n = mesh->mFaces[f].mNumIndices;
      if (n == 0 || mesh->mFaces[f].mIndices == nullptr)
        fail("{}: face {} of mesh {} has no corners: the file is malformed (cut short, or its header does not describe its data)", path, f,
             mi);
      types |= n == 1 ? aiPrimitiveType_POINT : n == 2 ? aiPrimitiveType_LINE : n == 3 ? aiPrimitiveType_TRIANGLE : aiPrimitiveType_POLYGON;
    }
    mesh->mPrimitiveTypes = types;
  }
  ai = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType | join);
  if (ai == nullptr) fail("{}: cannot read mesh: {}", path, importer.GetErrorString());
  if (!ai->HasMeshes()) fail("{}: contains no meshes", path);

  // Materials: Phong colours and the diffuse texture
  std::map<std::string, int> cache;
  const auto material_base = static_cast<uint32_t>(scene.materials.size());
  const fs::path dir = fs::path(path).parent_path();
  for (unsigned i = 0; i < ai->mNumMaterials; ++i) {
    const aiMaterial* m = ai->mMaterials[i];
    Material mat;
    aiString name;
    if (m->Get(AI_MATKEY_NAME, name) == AI_SUCCESS) mat.name = name.C_Str();
    mat.diffuse = diffuse_override.value_or(colour(m, AI_MATKEY_COLOR_DIFFUSE, glm::vec3(0.8f)));
    mat.specular = colour(m, AI_MATKEY_COLOR_SPECULAR, glm::vec3(0.0f));
    float shininess = 32.0f;
    if (m->Get(AI_MATKEY_SHININESS, shininess) == AI_SUCCESS && shininess > 0) mat.shininess = shininess;
    aiString tex;
    if (!diffuse_override && m->GetTexture(aiTextureType_DIFFUSE, 0, &tex) == AI_SUCCESS && tex.length > 0) {
      std::string rel = tex.C_Str();
      std::replace(rel.begin(), rel.end(), '\\', '/');
      mat.diffuse_texture = load_texture(scene, cache, dir / rel);
      if (mat.diffuse_texture >= 0) mat.diffuse = glm::vec3(1.0f);
    }
    scene.materials.push_back(mat);
  }
  if (ai->mNumMaterials == 0) scene.materials.push_back(Material{});

  // Geometry: one MeshData per Assimp mesh, all copied before Assimp's scene is freed (so that its
  // copy and foveal's are never held together with the scene's arrays); append_mesh then transforms
  // each and drops degenerate triangles
  struct Part {
    MeshData data;
    uint32_t material_id;
    std::string name;
  };
  std::vector<Part> parts;
  for (unsigned mi = 0; mi < ai->mNumMeshes; ++mi) {
    const aiMesh* mesh = ai->mMeshes[mi];
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    MeshData data;
    data.positions.reserve(mesh->mNumVertices);
    if (mesh->HasNormals()) data.normals.reserve(mesh->mNumVertices);
    if (mesh->HasTextureCoords(0)) data.uvs.reserve(mesh->mNumVertices);
    data.triangles.reserve(mesh->mNumFaces);
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      data.positions.emplace_back(mesh->mVertices[v].x, mesh->mVertices[v].y, mesh->mVertices[v].z);
      if (mesh->HasNormals()) data.normals.emplace_back(mesh->mNormals[v].x, mesh->mNormals[v].y, mesh->mNormals[v].z);
      if (mesh->HasTextureCoords(0)) data.uvs.emplace_back(mesh->mTextureCoords[0][v].x, mesh->mTextureCoords[0][v].y);
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f)
      if (mesh->mFaces[f].mNumIndices == 3)
        data.triangles.emplace_back(mesh->mFaces[f].mIndices[0], mesh->mFaces[f].mIndices[1], mesh->mFaces[f].mIndices[2]);
    const uint32_t material_id = material_base + (mesh->mMaterialIndex < ai->mNumMaterials ? mesh->mMaterialIndex : 0);
    parts.push_back({std::move(data), material_id, mesh->mName.C_Str()});
  }
  importer.FreeScene();
  size_t added = 0, vertices = 0, triangles = 0;
  for (const Part& part : parts) {
    vertices += part.data.positions.size();
    triangles += part.data.triangles.size();
  }
  reserve_mesh_space(scene, vertices, triangles);
  for (Part& part : parts) {
    const size_t before = scene.triangles.size();
    try {
      append_mesh(scene, part.data, part.material_id, transform);
    } catch (const Error& e) {
      fail("{}: mesh '{}': {}", path, part.name, e.what());
    }
    part.data = MeshData{};  // freed as soon as it is in the scene
    added += scene.triangles.size() - before;
  }
  if (added == 0) fail("{}: contains no usable triangles", path);
}

}  // namespace foveal
