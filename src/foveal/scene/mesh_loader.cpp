// foveal/scene/mesh_loader.cpp — meshes through Assimp (OBJ+MTL, PLY, glTF, …) and their textures.
#include "foveal/scene/scene.h"
#include "foveal/util/error.h"
#include "foveal/util/image_file.h"
#include "foveal/util/text.h"

#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/core.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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

// A PLY header must end in an "end_header" line before the file does: Assimp 5.2's PLY reader
// loops for ever where it does not (a file cut short in its header, "end_header" followed by data
// on the same line, or by nothing; found by mutating PLY files), so that is checked here first.
// The header is read up to 1 MiB: PLY headers are a few hundred bytes, comments included.
void check_ply_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(size_t(1) << 20, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  if (!head.starts_with("ply\n") && !head.starts_with("ply\r\n")) fail("{}: not a PLY file (it does not start with a line 'ply')", path);
  size_t line = 1;
  for (size_t at = 0; at < head.size(); ++line) {
    const size_t end = head.find('\n', at);
    if (end == std::string::npos) break;  // the last line has no end: not a whole header line
    std::string_view text(head.data() + at, end - at);
    while (!text.empty() && (text.back() == '\r' || text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
    if (text == "end_header") return;
    at = end + 1;
  }
  fail("{}: a PLY header without an 'end_header' line (read {} lines): the file is cut short or is not a PLY file", path, line - 1);
}

// The files Assimp opens, checked first where its readers crash on malformed ones: a material
// library (.mtl) with a statement before any "newmtl" line makes Assimp 5.2's MTL reader write to
// a material that does not exist (a segmentation fault; found by mutating MTL files). Such a file
// is not opened, and the problem, kept here, becomes the error once Assimp returns.
class CheckedFiles : public Assimp::DefaultIOSystem {
 public:
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    std::string ext = std::filesystem::path(file).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext == ".mtl" && Exists(file)) {  // (Assimp may open it more than once)
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
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  {
    // Assimp picks a reader by the extension, and by the content where the extension is not its
    std::ifstream in(path, std::ios::binary);
    char magic[4] = {};
    in.read(magic, 4);
    if (ext == ".ply" || (std::string_view(magic, 3) == "ply" && (magic[3] == '\n' || magic[3] == '\r'))) check_ply_header(path);
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
