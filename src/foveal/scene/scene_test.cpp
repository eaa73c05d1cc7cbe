// Tests of scene loading: Assimp meshes, scene JSON, built-ins and bad input.
#include "foveal/scene/scene.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace foveal;
namespace fs = std::filesystem;

namespace {

// A file in a fresh temporary folder, removed with the test.
struct TempDir {
  fs::path dir;
  TempDir()
      : dir(fs::temp_directory_path() / fs::path("foveal_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
                                                 ::testing::UnitTest::GetInstance()->current_test_info()->name())) {
    fs::create_directories(dir);
  }
  ~TempDir() { fs::remove_all(dir); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir / name, std::ios::binary) << text;
    return (dir / name).string();
  }
};

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

const char* kQuadObj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";

}  // namespace

TEST(Scene, LoadsObjAndComputesMissingNormals) {
  TempDir t;
  const Scene s = load_scene(t.write("quad.obj", kQuadObj));
  ASSERT_EQ(s.triangles.size(), 2u);
  for (const auto& n : s.normals) EXPECT_NEAR(std::abs(n.z), 1.0f, 1e-6f);
  EXPECT_EQ(s.bounds().hi, glm::vec3(1, 1, 0));
}

TEST(Scene, SkipsDegenerateTriangles) {
  TempDir t;
  const Scene s = load_scene(t.write("degenerate.obj", std::string(kQuadObj) + "v 2 0 0\nf 1 2 5\nf 2 2 3\n"));
  EXPECT_EQ(s.triangles.size(), 2u);
  EXPECT_EQ(s.skipped_triangles, 2u);
  for (const auto& n : s.normals) EXPECT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z));
}

// A vertex beyond ±1e15 (a corrupt binary PLY gave 9.4e21) drops its triangles like a non-finite
// one: the camera framing the scene stays finite (it was not, and Embree aborted the process)
TEST(Scene, SkipsTrianglesBeyondTheCoordinateRange) {
  TempDir t;
  const Scene s =
      load_scene(t.write("far.obj", std::string(kQuadObj) + "v -9.4e21 0 0\nf 5 2 3\nv 0 0 2e15\nf 1 2 6\nv 0 0 9e14\nf 1 2 7\n"));
  EXPECT_EQ(s.triangles.size(), 3u);  // the quad's two and the one within range
  EXPECT_EQ(s.skipped_triangles, 2u);
  EXPECT_LE(s.bounds().hi.z, kMaxSceneCoordinate);
  const Camera camera = default_camera(s);
  EXPECT_TRUE(std::isfinite(glm::dot(camera.eye - camera.look, camera.eye - camera.look)));
}

TEST(Scene, LoadsPlyWithCrlfAndObjMaterials) {
  TempDir t;
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(load_scene(t.write("tri.ply", ply)).triangles.size(), 1u);
  t.write("m.mtl", "newmtl red\nKd 0.9 0.1 0.1\n");
  const Scene s = load_scene(t.write("crlf.obj", "mtllib m.mtl\r\nusemtl red\r\nv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3 \r\n"));
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_NEAR(s.materials[s.material_ids[0]].diffuse.r, 0.9f, 1e-6f);
}

TEST(Scene, LoadsGltf) {
  TempDir t;
  // One triangle: positions (3 × vec3) and uint16 indices in an embedded base64 buffer
  const std::string gltf = R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
    "nodes": [{"mesh": 0, "translation": [0, 0, 5]}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
    "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                  {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]})";
  const Scene s = load_scene(t.write("tri.gltf", gltf));
  ASSERT_EQ(s.triangles.size(), 1u);
  EXPECT_EQ(s.bounds().lo.z, 5.0f);  // the node's transform is applied
  EXPECT_NEAR(std::abs(s.normals[0].z), 1.0f, 1e-6f);
}

TEST(Scene, ObjTexturesAreSampledInLinearColour) {
  TempDir t;
  // A 2×2 texture, all texels sRGB (255, 128, 0), bound with map_Kd
  const std::string ppm = std::string("P6\n2 2\n255\n") + std::string("\xff\x80\x00\xff\x80\x00\xff\x80\x00\xff\x80\x00", 12);
  t.write("tex.ppm", ppm);
  t.write("m.mtl", "newmtl t\nKd 1 1 1\nmap_Kd tex.ppm\n");
  const Scene s =
      load_scene(t.write("tex.obj", "mtllib m.mtl\nusemtl t\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n"));
  ASSERT_EQ(s.textures.size(), 1u);
  const Material& m = s.materials[s.material_ids[0]];
  ASSERT_GE(m.diffuse_texture, 0);
  const glm::vec3 c = s.textures[m.diffuse_texture].sample({0.3f, 0.3f});
  EXPECT_NEAR(c.r, 1.0f, 1e-6f);
  EXPECT_NEAR(c.g, 0.2158605f, 1e-5f);  // sRGB 128/255 decoded
  EXPECT_NEAR(c.b, 0.0f, 1e-6f);
}

// A texture meets the same checks as every image foveal reads: content of another format under an
// image's name (a DICOM signature after a broken PPM one, which aborted the process in OpenCV's
// DICOM decoder) and a header beyond the size cap are warnings naming the file and the reason,
// and the material keeps its colour
TEST(Scene, HostileTexturesAreWarnedAboutAndSkipped) {
  TempDir t;
  t.write("dicom.jpg", std::string("P6\x01\xff", 4) + std::string(124, '2') + "DICM" + std::string(16, '\0'));
  t.write("huge.ppm", "P6\n30000 30000\n255\n" + std::string(12, '\0'));
  for (const char* texture : {"dicom.jpg", "huge.ppm"}) {
    t.write("m.mtl", std::string("newmtl t\nKd 0.5 0.25 1\nmap_Kd ") + texture + "\n");
    testing::internal::CaptureStderr();
    const Scene s =
        load_scene(t.write("tex.obj", "mtllib m.mtl\nusemtl t\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n"));
    const std::string warned = testing::internal::GetCapturedStderr();
    EXPECT_TRUE(s.textures.empty()) << texture;
    EXPECT_LT(s.materials[s.material_ids[0]].diffuse_texture, 0) << texture;
    EXPECT_NEAR(s.materials[s.material_ids[0]].diffuse.g, 0.25f, 1e-6f) << texture;
    EXPECT_NE(warned.find(std::string(texture) + "' could not be read"), std::string::npos) << warned;
    EXPECT_NE(warned.find(texture == std::string("dicom.jpg") ? "not a PNG, JPEG" : "30000x30000 pixels"), std::string::npos) << warned;
  }
}

TEST(Scene, BadMeshesGiveClearErrors) {
  TempDir t;
  EXPECT_NE(error_of([&] { load_scene((t.dir / "missing.obj").string()); }).find("no such file"), std::string::npos);
  EXPECT_NE(error_of([&] { load_scene(t.write("empty.obj", "")); }).find("empty"), std::string::npos);
  EXPECT_NE(error_of([&] { load_scene(t.write("nothing.obj", "# only a comment\nv 0 0 0\n")); }), "");
  EXPECT_NE(error_of([&] { load_scene(t.write("garbage.ply", "ply\nformat ascii 1.0\nelement vertex 3\nend_header\nxx\n")); }), "");
  EXPECT_NE(error_of([&] { load_scene(t.write("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")); }).find("no usable triangles"),
            std::string::npos);
  EXPECT_NE(error_of([&] { load_scene("builtin:teapot"); }).find("known: box"), std::string::npos);
}

// Malformed PLY files that Assimp 5.2 loops on for ever or aborts the process on (found by mutating
// small PLY files) are refused with the file's name: a header without an "end_header" line (cut
// short; the marker run into the data; the file ending at it; PLY content under another name), and
// a binary file whose header does not describe its data (a property without a name), which gave
// faces of no corners. The same file with its header whole still reads.
TEST(Scene, MalformedPlyFilesAreRefusedNotHungOrAborted) {
  TempDir t;
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\n";
  const std::string data = "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(load_scene(t.write("whole.ply", header + "end_header\n" + data)).triangles.size(), 1u);
  for (const auto& [name, text] :
       std::vector<std::pair<std::string, std::string>>{{"cut.ply", header.substr(0, 40)},
                                                        {"run-on.ply", header + "end_headerB" + data},
                                                        {"ends.ply", header + "end_header"},
                                                        {"sniffed.mesh", header + "end_he9der\n" + data},
                                                        {"typo.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty flaot x\n"}}) {
    const std::string error = error_of([&] { load_scene(t.write(name, text)); });
    EXPECT_NE(error.find(name + ": a PLY header without an 'end_header' line"), std::string::npos) << error;
  }
  std::string binary =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float \n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  binary.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
  const unsigned char face[13] = {3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0};
  binary.append(reinterpret_cast<const char*>(face), sizeof face);
  const std::string error = error_of([&] { load_scene(t.write("nameless.ply", binary)); });
  EXPECT_NE(error.find("nameless.ply: face 0 of mesh 0 has no corners"), std::string::npos) << error;
  const size_t hole = binary.find("float \n");
  binary.replace(hole, 7, "float z\n");
  EXPECT_EQ(load_scene(t.write("named.ply", binary)).triangles.size(), 1u);
  // A list length no face has (Assimp allocated 20 GB for one in a 330-byte file) and an element
  // count beyond what the file holds are refused before Assimp reads them, binary and ASCII
  std::string huge =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uint int vertex_indices\nend_header\n";
  huge.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
  const unsigned char huge_face[16] = {3, 0, 0, 0x30, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0};  // length 0x30000003
  huge.append(reinterpret_cast<const char*>(huge_face), sizeof huge_face);
  std::string error2 = error_of([&] { load_scene(t.write("huge-list.ply", huge)); });
  EXPECT_NE(error2.find("huge-list.ply: face 0 of 1 holds a list of 805306371 values (a face has at most 32767 corners)"),
            std::string::npos)
      << error2;
  error2 = error_of([&] { load_scene(t.write("huge-ascii.ply", header + "end_header\n" + "0 0 0\n1 0 0\n0 1 0\n300000000 0 1 2\n")); });
  EXPECT_NE(error2.find("face 0 of 1 holds a list of 300000000 values"), std::string::npos) << error2;
  std::string many = header + "end_header\n" + data;
  many.replace(many.find("element face 1"), 14, "element face 2000000000");
  error2 = error_of([&] { load_scene(t.write("many.ply", many)); });
  EXPECT_NE(error2.find("element 'face' claims 2000000000 instances, more than the"), std::string::npos) << error2;
}

// A material library with a statement before any "newmtl" line crashed Assimp 5.2's MTL reader (a
// segmentation fault; found by mutating MTL files): it is an error naming the file and line.
// Comments and blank lines before the first material are fine.
TEST(Scene, AMaterialLibraryWithoutNewmtlFirstIsRefused) {
  TempDir t;
  t.write("tex.ppm", std::string("P6\n1 1\n255\n\xff\x80\x00", 14));
  const std::string obj = "mtllib m.mtl\nusemtl t\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";
  t.write("m.mtl", "# made by hand\n\nKd 0.5 0.5 0.5\nmap_Kd tex.ppm\n");
  const std::string error = error_of([&] { load_scene(t.write("broken.obj", obj)); });
  EXPECT_NE(error.find("m.mtl:3: 'Kd' before any 'newmtl' line"), std::string::npos) << error;
  t.write("m.mtl", "# made by hand\n\nnewmtl t\nKd 0.5 0.5 0.5\nmap_Kd tex.ppm\n");
  const Scene s = load_scene(t.write("whole.obj", obj));
  EXPECT_EQ(s.textures.size(), 1u);
}

TEST(Scene, JsonWithTransformsCamerasAndLights) {
  TempDir t;
  t.write("quad.obj", kQuadObj);
  const std::string json = R"({
    "meters_per_unit": 0.01, "ao_distance": 3,
    "meshes": [ {"file": "quad.obj", "translate": [10, 0, 0], "scale": 2},
                {"shape": "sphere", "centre": [0, 5, 0], "radius": 1, "segments": 16} ],
    "cameras": [ {"name": "a", "eye": [0, 0, 10], "look": [0, 0, 0], "fov": 30} ],
    "lights": [ {"type": "directional", "direction": [0, -2, 0]} ] })";
  const Scene s = load_scene(t.write("scene.json", json));
  EXPECT_NEAR(s.meters_per_unit, 0.01, 1e-9);
  EXPECT_FLOAT_EQ(*s.ao_distance, 3.0f);
  EXPECT_EQ(s.positions[2], glm::vec3(12, 2, 0));  // scaled, then translated
  EXPECT_EQ(find_camera(s, "a").fov_deg, 30.0f);
  EXPECT_EQ(s.lights.at(0).vector, glm::vec3(0, -1, 0));
  EXPECT_GT(s.triangles.size(), 100u);
  EXPECT_THROW(find_camera(s, "b"), Error);
}

TEST(Scene, JsonErrorsNameTheFileAndField) {
  TempDir t;
  auto err = [&](const std::string& json) { return error_of([&] { load_scene(t.write("bad.json", json)); }); };
  EXPECT_NE(err("{ \"meshes\": [ }").find("line 1"), std::string::npos);
  EXPECT_NE(err(R"({"ao_distance": 1e999})").find("invalid JSON"), std::string::npos);  // found by fuzzing
  EXPECT_NE(err(R"({"meshes": [{"shape": "box", "min": [0,0,0], "max": [1,1,1]}], "camras": []})").find("unknown key 'camras'"),
            std::string::npos);
  EXPECT_NE(err(R"({"meshes": [{"shape": "sphere", "centre": [0,0,0], "radius": -1}]})").find("meshes[0].radius"), std::string::npos);
  EXPECT_NE(err(R"({"meshes": [{"file": "nope.obj"}]})").find("nope.obj: no such file"), std::string::npos);
  EXPECT_NE(err(R"({"meshes": []})").find("non-empty"), std::string::npos);
  EXPECT_NE(err(R"({"meshes": [{"shape": "box", "min": [0,0], "max": [1,1,1]}]})").find("meshes[0].min"), std::string::npos);
  EXPECT_NE(err(R"({"meshes": [{"shape": "box", "min": [0,0,0], "max": [1,1,1]}], "cameras": [{"eye": [0,0,0], "look": [0,0,0]}]})")
                .find("eye and look"),
            std::string::npos);
}

TEST(Scene, BuiltinsAreThePapersSetting) {
  const Scene box = make_builtin_scene("box");
  EXPECT_GE(box.triangles.size(), 100000u);
  EXPECT_EQ(box.cameras.size(), 3u);
  const Scene sp = make_builtin_scene("sphere-plane");
  EXPECT_TRUE(std::isinf(*sp.ao_distance));
  for (const auto& n : box.normals) ASSERT_NEAR(glm::length(n), 1.0f, 1e-4f);
}

TEST(Scene, RealScenesLoadWhenPresent) {
  const std::string data = FOVEAL_DATA_DIR;
  const std::string dragon = data + "/scenes/dragon/dragon.obj";
  if (!fs::exists(dragon)) GTEST_SKIP() << "skipped: " << dragon << " absent";
  const Scene s = load_scene(dragon);
  EXPECT_EQ(s.triangles.size(), 100000u);  // counts from the data README
  EXPECT_NEAR(s.bounds().hi.y, 9.9399f, 1e-3f);
  const Scene box = load_scene(std::string(FOVEAL_SOURCE_DIR) + "/scenes/dragon-box.json");
  EXPECT_EQ(box.triangles.size(), 100010u);
  EXPECT_EQ(box.cameras.size(), 3u);
}

TEST(Scene, AnOrbitTurnsTheEyeAboutTheUpAxisThroughTheLookPoint) {
  Camera c;
  c.eye = {1, 2, 5};
  c.look = {1, 2, 0};
  const Camera quarter = orbit_camera(c, 90);
  EXPECT_NEAR(quarter.eye.x, 6, 1e-5);  // from +z towards +x about +y
  EXPECT_NEAR(quarter.eye.y, 2, 1e-5);
  EXPECT_NEAR(quarter.eye.z, 0, 1e-5);
  EXPECT_EQ(quarter.look, c.look);
  EXPECT_EQ(quarter.fov_deg, c.fov_deg);
  // About a tilted up axis: the distance to the look point and the angle to the axis are kept
  c.up = glm::normalize(glm::vec3(0, 1, 1));
  const Camera turned = orbit_camera(c, 37);
  EXPECT_NEAR(glm::length(turned.eye - turned.look), 5, 1e-5);
  EXPECT_NEAR(glm::dot(turned.eye - turned.look, c.up), glm::dot(c.eye - c.look, c.up), 1e-5);
  const Camera back = orbit_camera(turned, -37);
  EXPECT_NEAR(glm::length(back.eye - c.eye), 0, 1e-5);
  EXPECT_EQ(orbit_camera(c, 0).eye, c.eye);
}

TEST(Scene, CameraPathsInterpolateThroughNamedCameras) {
  const std::string text = R"({"meshes": [{"shape": "sphere", "radius": 1, "centre": [0, 0, 0]}],
    "cameras": [{"name": "a", "eye": [0, 0, 10], "look": [0, 0, 0], "fov": 40},
                {"name": "b", "eye": [10, 0, 10], "look": [10, 0, 0], "fov": 60},
                {"name": "c", "eye": [10, 10, 10], "look": [10, 10, 0], "fov": 60}],
    "camera_paths": [{"name": "walk", "cameras": ["a", "b", "c"], "steps": 5}]})";
  const Scene s = parse_scene_json(text, "path.json", ".");
  const CameraPath& p = find_camera_path(s, "walk");
  ASSERT_EQ(p.keys.size(), 3u);
  EXPECT_EQ(p.at(1).eye, glm::vec3(0, 0, 10));  // first key at step 1
  EXPECT_EQ(p.at(2).eye, glm::vec3(5, 0, 10));  // halfway to b
  EXPECT_FLOAT_EQ(p.at(2).fov_deg, 50.0f);
  EXPECT_EQ(p.at(3).eye, glm::vec3(10, 0, 10));    // b at the middle step
  EXPECT_EQ(p.at(5).eye, glm::vec3(10, 10, 10));   // last key at the last step
  EXPECT_EQ(p.at(99).eye, glm::vec3(10, 10, 10));  // held afterwards
  EXPECT_THROW(find_camera_path(s, "run"), Error);
  for (const char* bad :
       {R"("camera_paths": [{"cameras": ["a", "x"]}])", R"("camera_paths": [{"cameras": ["a"]}])",
        R"("camera_paths": [{"cameras": ["a", "b"], "steps": 1.5}])", R"("camera_paths": [{"cameras": ["a", "b"], "speed": 2}])"}) {
    const std::string doc =
        std::string(
            R"({"meshes": [{"shape": "sphere", "radius": 1, "centre": [0, 0, 0]}], "cameras": [{"name": "a", "eye": [0, 0, 10], "look": [0, 0, 0]},
      {"name": "b", "eye": [1, 0, 10], "look": [0, 0, 0]}], )") +
        bad + "}";
    try {
      parse_scene_json(doc, "bad.json", ".");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("bad.json: camera_paths[0]"), std::string::npos) << e.what();
    }
  }
}

// A scene JSON saved with a UTF-8 byte-order mark and CRLF line ends reads as the plain one.
TEST(Scene, JsonWithByteOrderMarkAndCrlf) {
  const std::string text =
      "{\"meshes\": [{\"shape\": \"sphere\", \"radius\": 1, \"centre\": [0, 0, 0]}],\r\n"
      " \"cameras\": [{\"name\": \"a\", \"eye\": [0, 0, 10], \"look\": [0, 0, 0], \"fov\": 40}]}\r\n";
  const Scene plain = parse_scene_json(text, "s.json", ".");
  const Scene bom = parse_scene_json("\xEF\xBB\xBF" + text, "s.json", ".");
  EXPECT_EQ(bom.triangles.size(), plain.triangles.size());
  ASSERT_EQ(bom.cameras.size(), 1u);
  EXPECT_EQ(bom.cameras[0].eye, plain.cameras[0].eye);
}
