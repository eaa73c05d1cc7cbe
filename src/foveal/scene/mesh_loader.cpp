// foveal/scene/mesh_loader.cpp — meshes through Assimp (OBJ+MTL, PLY, glTF, …) and their textures.
#include "foveal/scene/scene.h"
#include "foveal/util/error.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/core.h>
#include <glm/gtc/matrix_inverse.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <map>

namespace foveal {
namespace {

// Load a texture once per scene; a missing or unreadable texture is a warning, not an error.
int load_texture(Scene& scene, std::map<std::string, int>& cache, const std::filesystem::path& file) {
  const std::string key = file.lexically_normal().string();
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  cv::Mat image = cv::imread(key, cv::IMREAD_COLOR);
  if (image.empty()) {
    fmt::print(stderr, "foveal: warning: texture '{}' could not be read; using the material colour\n", key);
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

glm::vec3 colour(const aiMaterial* m, const char* key, unsigned type, unsigned index, glm::vec3 fallback) {
  aiColor3D c;
  if (m->Get(key, type, index, c) != AI_SUCCESS) return fallback;
  return {c.r, c.g, c.b};
}

}  // namespace

void append_mesh_file(Scene& scene, const std::string& path, const glm::mat4& transform,
                      std::optional<glm::vec3> diffuse_override) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) fail("{}: no such file", path);
  if (fs::file_size(path, ec) == 0) fail("{}: file is empty", path);
  // Triangulate, bake node transforms, drop points and lines; normals are ours (see below)
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const unsigned flags = aiProcess_Triangulate | aiProcess_PreTransformVertices | aiProcess_SortByPType |
                         aiProcess_JoinIdenticalVertices | aiProcess_ValidateDataStructure;
  const aiScene* ai = importer.ReadFile(path, flags);
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

  // Geometry: positions and uvs transformed to world space; degenerate triangles dropped
  const glm::mat3 normal_matrix = glm::inverseTranspose(glm::mat3(transform));
  size_t added = 0;
  for (unsigned mi = 0; mi < ai->mNumMeshes; ++mi) {
    const aiMesh* mesh = ai->mMeshes[mi];
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const auto base = static_cast<uint32_t>(scene.positions.size());
    const size_t first_triangle = scene.triangles.size();
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      scene.positions.push_back(glm::vec3(transform * glm::vec4(p.x, p.y, p.z, 1.0f)));
      glm::vec3 n(0.0f);
      if (mesh->HasNormals()) n = normal_matrix * glm::vec3(mesh->mNormals[v].x, mesh->mNormals[v].y, mesh->mNormals[v].z);
      scene.normals.push_back(n);
      scene.uvs.push_back(mesh->HasTextureCoords(0) ? glm::vec2(mesh->mTextureCoords[0][v].x, mesh->mTextureCoords[0][v].y)
                                                    : glm::vec2(0.0f));
    }
    const uint32_t material_id =
        material_base + (mesh->mMaterialIndex < ai->mNumMaterials ? mesh->mMaterialIndex : 0);
    std::vector<glm::vec3> accumulated(mesh->mNumVertices, glm::vec3(0.0f));
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;
      const glm::uvec3 t(face.mIndices[0], face.mIndices[1], face.mIndices[2]);
      if (t.x >= mesh->mNumVertices || t.y >= mesh->mNumVertices || t.z >= mesh->mNumVertices)
        fail("{}: mesh '{}' face {} has a vertex index out of range", path, mesh->mName.C_Str(), f);
      const glm::vec3 a = scene.positions[base + t.x], b = scene.positions[base + t.y], c = scene.positions[base + t.z];
      const glm::vec3 n = glm::cross(b - a, c - a);
      const float area2 = glm::dot(n, n);
      if (!std::isfinite(area2) || area2 <= 0.0f || !std::isfinite(a.x + a.y + a.z + b.x + b.y + b.z + c.x + c.y + c.z)) {
        ++scene.skipped_triangles;
        continue;
      }
      for (int k = 0; k < 3; ++k) accumulated[t[k]] += n;
      scene.triangles.push_back(t + glm::uvec3(base));
      scene.material_ids.push_back(material_id);
    }
    // Missing or broken normals: area-weighted average of the adjacent faces
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      glm::vec3& n = scene.normals[base + v];
      const float len = glm::length(n);
      if (len > 0 && std::isfinite(len)) {
        n /= len;
      } else {
        const float alen = glm::length(accumulated[v]);
        n = alen > 0 && std::isfinite(alen) ? accumulated[v] / alen : glm::vec3(0, 1, 0);
      }
    }
    added += scene.triangles.size() - first_triangle;
  }
  if (added == 0) fail("{}: contains no usable triangles", path);
}

}  // namespace foveal
