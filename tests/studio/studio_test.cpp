// qs-studio's server side: path rules, hostile requests (traversal, links out, huge bodies, bad
// JSON, non-mesh uploads: a 4xx with a message and nothing changed on disk), landmark files
// written exactly, the seed-loop preview, runs (one at a time, a failed run leaves the folder as
// it was) and the real HTTP server. Meshes are made in code.
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "qs/io/write_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"
#include "qs/studio/paths.h"
#include "qs/studio/server.h"
#include "qs/studio/studio.h"
#include "studio_requests.h"
#include "../common/test_support.h"

// After Eigen (through qs/core/mesh.h): httplib pulls in <resolv.h>, whose `_res` macro breaks
// Eigen's headers.
#include <httplib.h>

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace qs::studio;
using qs::studio::test::error_of;
using qs::studio::test::get;
using qs::studio::test::post;

using qs::test::read_bytes;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    std::string t = (fs::temp_directory_path() / "qs-studio-test-XXXXXX").string();
    path = mkdtemp(t.data());
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

void write_text(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

/// Every entry under dir: path -> contents (files), link target (links) or "<dir>".
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it) {
    const std::string rel = fs::relative(it->path(), dir).generic_string();
    if (it->is_symlink()) {
      out[rel] = "-> " + fs::read_symlink(it->path()).string();
      it.disable_recursion_pending();
    } else if (it->is_directory()) {
      out[rel] = "<dir>";
    } else {
      out[rel] = read_bytes(it->path());
    }
  }
  return out;
}


/// A folder with a sphere, a web folder with a page, and a secret outside both.
struct Fixture {
  TempDir tmp;
  fs::path root, web, outside;
  Fixture() {
    root = tmp.path / "meshes";
    web = tmp.path / "web";
    outside = tmp.path / "outside";
    fs::create_directories(root);
    fs::create_directories(web / "app");
    fs::create_directories(outside);
    write_text(web / "index.html", "<html>studio page</html>");
    write_text(web / "app" / "app.js", "// app");
    write_text(outside / "secret.txt", "TOP-SECRET-CONTENT-42");
    qs::io::write_mesh(outside / "secret.obj", qs::shapes::icosphere(1));
    qs::io::write_mesh(root / "sphere.obj", qs::shapes::icosphere(3));
  }
  StudioOptions options() const {
    StudioOptions o;
    o.folder = root;
    o.web_dir = web;
    o.tools_dir = QS_TOOLS_DIR;
    return o;
  }
};

json seeds_json(const std::array<int, 4>& faces) {
  json s = json::array();
  for (int f : faces) s.push_back({{"face", f}, {"bary", {0.2, 0.3, 0.5}}});
  return s;
}

}  // namespace

TEST(StudioPaths, RefusesBadSyntax) {
  for (const std::string& bad :
       {std::string(""), std::string("/etc/passwd"), std::string(".."), std::string("../x.obj"), std::string("a/../../x"),
        std::string("a//b"), std::string("a/"), std::string("a\\..\\b"), std::string(".hidden"),
        std::string("runs/.run-1.partial/x"), std::string("a\0b", 3), std::string("a\nb"), std::string(2000, 'a')}) {
    EXPECT_THROW(check_relative_path(bad), PathRefused) << "accepted: " << bad;
  }
  for (const std::string good : {"a.obj", "runs/run-1/morph.glb", "x..y.obj", "a b.obj"})
    EXPECT_NO_THROW(check_relative_path(good)) << good;
  try {
    check_relative_path("../x");
  } catch (const PathRefused& e) {
    EXPECT_NE(std::string(e.what()).find("'..'"), std::string::npos) << e.what();
  }
}

TEST(StudioPaths, LinksOutOfTheFolderAreRefused) {
  Fixture fx;
  const fs::path root = fs::canonical(fx.root);
  fs::create_symlink(fx.outside / "secret.txt", fx.root / "link.txt");
  fs::create_directory_symlink(fx.outside, fx.root / "out");
  write_text(fx.root / "real.txt", "inside");
  fs::create_symlink(fx.root / "real.txt", fx.root / "inner_link.txt");
  EXPECT_THROW(resolve_existing(root, "link.txt"), PathRefused);
  EXPECT_THROW(resolve_existing(root, "out/secret.txt"), PathRefused);
  EXPECT_THROW(resolve_for_writing(root, "out/new.txt"), PathRefused);
  EXPECT_THROW(resolve_for_writing(root, "link.txt"), PathRefused);
  EXPECT_THROW(resolve_for_writing(root, "inner_link.txt"), PathRefused);  // never written through
  EXPECT_EQ(resolve_existing(root, "inner_link.txt"), root / "real.txt");  // read: stays inside
  EXPECT_THROW(resolve_existing(root, "missing.txt"), qs::IoError);
  EXPECT_EQ(resolve_for_writing(root, "new.txt"), root / "new.txt");
  EXPECT_FALSE(fs::exists(root / "new.txt"));
}

TEST(Studio, HostileRequestsGet4xxAndChangeNothing) {
  Fixture fx;
  fs::create_symlink(fx.outside / "secret.obj", fx.root / "link.obj");
  fs::create_directory_symlink(fx.outside, fx.root / "out");
  write_text(fx.root / ".hidden.obj", "v 0 0 0\n");
  Studio studio(fx.options());
  const auto before = snapshot(fx.tmp.path);

  struct Case {
    Request req;
    int status;
    std::string words;  // a part of the message
  };
  std::vector<Case> cases = {
      {get("/files/../outside/secret.txt"), 403, "'..'"},
      {get("/files/out/secret.txt"), 403, "symbolic link"},
      {get("/files/link.obj"), 403, "symbolic link"},
      {get("/files//etc/passwd"), 403, "absolute"},
      {get("/files/.hidden.obj"), 403, "hidden"},
      {get("/files/none.obj"), 404, "not found"},
      {get("/api/mesh", {{"path", "../outside/secret.obj"}}), 403, "'..'"},
      {get("/api/mesh", {{"path", "/etc/passwd"}}), 400, "not a mesh"},
      {get("/api/mesh", {{"path", "link.obj"}}), 403, "symbolic link"},
      {get("/api/mesh"), 400, "missing query parameter 'path'"},
      {get("/app/../../outside/secret.txt"), 403, "'..'"},
      {get("/node_modules/evil/x.js"), 404, "not found"},
      {post("/api/landmarks", {{"name", "sphere.obj"}}, "{not json"), 400, "not valid JSON"},
      {post("/api/landmarks", {{"name", "sphere.obj"}}, std::string(2u << 20, ' ')), 413, "at most"},
      {post("/api/landmarks", {{"name", "sphere.obj"}}, json{{"seeds", seeds_json({99999, 1, 2, 3})}}.dump()), 400,
       "out of range"},
      {post("/api/landmarks", {{"name", "sphere.obj"}}, json{{"seeds", {1, 2, 3}}}.dump()), 400, "seed"},
      {post("/api/landmarks", {{"name", "sphere.obj"}}, R"({"bogus": 1})"), 400, "unknown key"},
      {post("/api/landmarks", {{"name", "sphere.obj"}}, R"([1, 2])"), 400, "JSON object"},
      {post("/api/landmarks", {{"name", "../outside/secret.obj"}}, "{}"), 403, "'..'"},
      {post("/api/landmarks", {{"name", "nothere.obj"}}, "{}"), 404, "not found"},
      {post("/api/landmarks", {{"name", "link.obj"}}, "{}"), 403, "symbolic link"},
      {post("/api/upload", {{"name", "junk.obj"}}, "hello, I am not a mesh\n"), 400, "not a mesh"},
      {post("/api/upload", {{"name", "junk.ply"}}, "ply\nformat binary_little_endian 1.0\nelement vertex 99999999\n"), 400,
       "not a mesh"},
      {post("/api/upload", {{"name", "tool.exe"}}, "MZ"), 400, "not a mesh file name"},
      {post("/api/upload", {{"name", "sphere.obj"}}, "v 0 0 0\n"), 409, "exists already"},
      {post("/api/upload", {{"name", "../evil.obj"}}, "v 0 0 0\n"), 403, "'..'"},
      {post("/api/upload", {{"name", "out/evil.obj"}}, "v 0 0 0\n"), 400, "'/'"},
      {post("/api/upload", {{"name", "empty.obj"}}, ""), 400, "empty"},
      {post("/api/run", {}, "{\"meshes\": [\"sphere.obj\""), 400, "not valid JSON"},
      {post("/api/run", {}, R"({"meshes": ["sphere.obj"], "level": 9})"), 400, "\"level\""},
      {post("/api/run", {}, R"({"meshes": ["sphere.obj"], "rm": "-rf"})"), 400, "unknown key"},
      {post("/api/run", {}, R"({"meshes": ["../outside/secret.obj"]})"), 403, "'..'"},
      {post("/api/run", {}, R"({"meshes": ["none.obj"]})"), 404, "not found"},
      {post("/api/run", {}, R"({"meshes": ["sphere.obj", "sphere.off"]})"), 400, "named 'sphere'"},
      {post("/api/run", {}, R"({"meshes": []})"), 400, "non-empty"},
      {post("/api/run", {}, std::string(2u << 20, ' ')), 413, "at most"},
      {post("/api/seed-loop", {{"name", "sphere.obj"}}, "nope"), 400, "not valid JSON"},
      {Request{"PUT", "/api/meshes", {}, ""}, 405, "not allowed"},
      {Request{"DELETE", "/api/meshes", {}, ""}, 400, "missing query parameter"},
      {Request{"DELETE", "/api/runs", {{"name", "../meshes"}}, ""}, 400, "not a run name"},
      {Request{"DELETE", "/api/meshes", {{"name", "../outside/secret.obj"}}, ""}, 403, ".."},
      {Request{"PUT", "/files/sphere.obj", {}, "x"}, 405, "not allowed"},
      {get("/api/nope"), 404, "no such API"},
  };
  for (const auto& c : cases) {
    const Response r = studio.handle(c.req);
    EXPECT_EQ(r.status, c.status) << c.req.method << " " << c.req.path << ": " << r.body;
    EXPECT_NE(error_of(r).find(c.words), std::string::npos)
        << c.req.method << " " << c.req.path << ": expected '" << c.words << "' in " << r.body;
    EXPECT_TRUE(r.file.empty()) << c.req.path;
  }
  EXPECT_EQ(snapshot(fx.tmp.path), before) << "a refused request changed the disk";
}

TEST(Studio, ServesThePageAndFolderFiles) {
  Fixture fx;
  Studio studio(fx.options());
  Response r = studio.handle(get("/"));
  EXPECT_EQ(r.status, 200);
  // three.js is not in this web folder: the page says what is missing instead of failing blank
  EXPECT_NE(r.body.find("three.js is not installed"), std::string::npos);
  fs::create_directories(fx.web / "node_modules/three/build");
  write_text(fx.web / "node_modules/three/build/three.module.js", "// three");
  r = studio.handle(get("/"));
  EXPECT_EQ(r.file, fs::canonical(fx.web / "index.html"));
  r = studio.handle(get("/node_modules/three/build/three.module.js"));
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.content_type, "application/x-javascript");
  r = studio.handle(get("/files/sphere.obj", {{"download", "1"}}));
  EXPECT_EQ(r.status, 200);
  EXPECT_TRUE(r.attachment);
  EXPECT_EQ(r.file, fs::canonical(fx.root / "sphere.obj"));
}

TEST(Studio, ListsMeshesWithFindingsInPlainWords) {
  Fixture fx;
  qs::io::write_mesh(fx.root / "disk.obj", qs::shapes::open_disk(3));
  qs::io::write_mesh(fx.root / "ring.off", qs::shapes::torus(12, 6));
  write_text(fx.root / "junk.stl", "solid x\nthis is not STL\n");
  write_text(fx.root / "notes.txt", "not a mesh, not listed");
  Studio studio(fx.options());
  const Response r = studio.handle(get("/api/meshes"));
  ASSERT_EQ(r.status, 200) << r.body;
  const json list = json::parse(r.body)["meshes"];
  std::map<std::string, json> by;
  for (const auto& m : list) by[m["name"]] = m;
  ASSERT_EQ(by.size(), 4u) << r.body;
  EXPECT_TRUE(by["sphere.obj"]["accepted"].get<bool>());
  EXPECT_NE(by["sphere.obj"]["summary"].get<std::string>().find("ready"), std::string::npos);
  EXPECT_FALSE(by["disk.obj"]["accepted"].get<bool>());
  EXPECT_NE(by["disk.obj"]["summary"].get<std::string>().find("holes"), std::string::npos);
  EXPECT_EQ(by["disk.obj"]["problems"][0]["kind"], "boundary_edges");
  EXPECT_FALSE(by["disk.obj"]["problems"][0]["message"].get<std::string>().empty());
  EXPECT_NE(by["ring.off"]["summary"].get<std::string>().find("handles"), std::string::npos);
  EXPECT_FALSE(by["junk.stl"]["read"].get<bool>());
  EXPECT_NE(by["junk.stl"]["summary"].get<std::string>().find("cannot be read"), std::string::npos);
}

TEST(Studio, SavesLandmarksThatQsReadsBackExactly) {
  Fixture fx;
  Studio studio(fx.options());
  const qs::TriMesh sphere = qs::shapes::icosphere(3);
  json body = {{"seeds", json::array()}, {"features", {{"nose", {{"face", 17}, {"bary", {0.1, 0.7, 0.2}}}}}}};
  const std::array<int, 4> faces = {0, 300, 600, 1000};
  const std::array<std::array<double, 3>, 4> bary = {{{0.25, 0.25, 0.5}, {1.0 / 3, 1.0 / 3, 1.0 / 3}, {0.6, 0.3, 0.1},
                                                     {0.123456789012345, 0.5, 0.376543210987655}}};
  for (int i = 0; i < 4; ++i) body["seeds"].push_back({{"face", faces[i]}, {"bary", bary[i]}});
  Response r = studio.handle(post("/api/landmarks", {{"name", "sphere.obj"}}, body.dump()));
  ASSERT_EQ(r.status, 200) << r.body;
  const fs::path file = fx.root / "sphere.landmarks.json";
  ASSERT_TRUE(fs::exists(file));
  for (const auto& e : fs::directory_iterator(fx.root))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << "left behind: " << e.path();
  const auto valid = qs::mesh::validate(sphere);
  const auto lm = qs::landmarks::read_landmarks(file, valid);
  ASSERT_EQ(lm.seeds.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(lm.seeds[i].where.face, faces[i]);
    const double sum = bary[i][0] + bary[i][1] + bary[i][2];
    for (int k = 0; k < 3; ++k) EXPECT_EQ(lm.seeds[i].where.bary[k], bary[i][k] / sum) << "seed " << i;
  }
  ASSERT_EQ(lm.features.size(), 1u);
  EXPECT_EQ(lm.features[0].name, "nose");
  // and the page gets the same references back
  r = studio.handle(get("/api/landmarks", {{"name", "sphere.obj"}}));
  ASSERT_EQ(r.status, 200) << r.body;
  const json back = json::parse(r.body);
  EXPECT_EQ(back["file"], "sphere.landmarks.json");
  EXPECT_EQ(back["seeds"][3]["face"], faces[3]);
  EXPECT_EQ(back["features"][0]["name"], "nose");
  EXPECT_EQ(back["features"][0]["face"], 17);
  // a second save replaces the file whole
  body["features"] = json::object();
  r = studio.handle(post("/api/landmarks", {{"name", "sphere.obj"}}, body.dump()));
  ASSERT_EQ(r.status, 200) << r.body;
  EXPECT_EQ(json::parse(read_bytes(file))["features"].size(), 0u);
}

TEST(Studio, LoadsMeshLabPickedPoints) {
  Fixture fx;
  Studio studio(fx.options());
  const qs::TriMesh sphere = qs::shapes::icosphere(3);
  std::ostringstream pp;
  pp.precision(17);
  pp << "<!DOCTYPE PickedPoints>\n<PickedPoints>\n";
  const char* names[] = {"seed0", "seed1", "seed2", "seed3", "tail"};
  const int verts[] = {0, 100, 200, 300, 400};
  for (int i = 0; i < 5; ++i) {
    const auto& p = sphere.positions[verts[i]];
    pp << " <point x=\"" << p.x() << "\" y=\"" << p.y() << "\" z=\"" << p.z() << "\" name=\"" << names[i] << "\" active=\"1\"/>\n";
  }
  pp << "</PickedPoints>\n";
  write_text(fx.root / "sphere.pp", pp.str());
  const Response r = studio.handle(get("/api/landmarks", {{"name", "sphere.obj"}}));
  ASSERT_EQ(r.status, 200) << r.body;
  const json j = json::parse(r.body);
  EXPECT_EQ(j["file"], "sphere.pp");
  ASSERT_EQ(j["seeds"].size(), 4u);
  ASSERT_EQ(j["features"].size(), 1u);
  for (int i = 0; i < 4; ++i) {
    const auto& t = sphere.faces[j["seeds"][i]["face"].get<int>()];
    qs::Vec3 p = qs::Vec3::Zero();
    for (int k = 0; k < 3; ++k) p += j["seeds"][i]["bary"][k].get<double>() * sphere.positions[t[k]];
    EXPECT_LT((p - sphere.positions[verts[i]]).norm(), 1e-9) << "seed" << i;
  }
}

TEST(Studio, SeedLoopPreviewJoinsTheSeeds) {
  Fixture fx;
  Studio studio(fx.options());
  const qs::TriMesh sphere = qs::shapes::icosphere(3);
  // four points inside faces around the equator, and a feature near a pole
  std::vector<int> faces;
  for (const qs::Vec3& dir : {qs::Vec3(1, 0, 0), qs::Vec3(0, 1, 0), qs::Vec3(-1, 0, 0), qs::Vec3(0, -1, 0)})
    faces.push_back(qs::landmarks::closest_surface_point(sphere, dir).face);
  const int pole = qs::landmarks::closest_surface_point(sphere, qs::Vec3(0, 0, 1)).face;
  json body = {{"seeds", json::array()}, {"features", {{"top", {{"face", pole}, {"bary", {0.3, 0.3, 0.4}}}}}}};
  for (int f : faces) body["seeds"].push_back({{"face", f}, {"bary", {0.2, 0.3, 0.5}}});
  const Response r = studio.handle(post("/api/seed-loop", {{"name", "sphere.obj"}}, body.dump()));
  ASSERT_EQ(r.status, 200) << r.body;
  const json j = json::parse(r.body);
  ASSERT_EQ(j["paths"].size(), 4u);
  auto seed_point = [&](int i) {
    const auto& t = sphere.faces[faces[i]];
    return qs::Vec3(0.2 * sphere.positions[t[0]] + 0.3 * sphere.positions[t[1]] + 0.5 * sphere.positions[t[2]]);
  };
  for (int i = 0; i < 4; ++i) {
    const auto& p = j["paths"][i];
    ASSERT_GE(p.size(), 6u);
    const qs::Vec3 first(p[0], p[1], p[2]), last(p[p.size() - 3], p[p.size() - 2], p[p.size() - 1]);
    EXPECT_LT((first - seed_point(i)).norm(), 1e-9) << "path " << i << " starts at its seed";
    EXPECT_LT((last - seed_point((i + 1) % 4)).norm(), 1e-9) << "path " << i << " ends at the next seed";
  }
  EXPECT_GT(j["length"].get<double>(), 0);
  // the same point twice: refused with a message
  body["seeds"][1] = body["seeds"][0];
  const Response bad = studio.handle(post("/api/seed-loop", {{"name", "sphere.obj"}}, body.dump()));
  EXPECT_EQ(bad.status, 400);
  EXPECT_FALSE(error_of(bad).empty());
}

TEST(Studio, UploadsAMesh) {
  Fixture fx;
  Studio studio(fx.options());
  const std::string obj = read_bytes(fx.outside / "secret.obj");
  const Response r = studio.handle(post("/api/upload", {{"name", "new.obj"}}, obj));
  EXPECT_EQ(r.status, 201) << r.body;
  EXPECT_EQ(read_bytes(fx.root / "new.obj"), obj);
}

TEST(StudioRun, RunsThePipelineOneRunAtATime) {
  Fixture fx;
  qs::io::write_mesh(fx.root / "egg.obj", qs::shapes::ellipsoid(1.0, 0.8, 1.3, 3));
  Studio studio(fx.options());
  const std::string req = R"({"meshes": ["sphere.obj", "egg.obj"], "level": 2, "bake_size": 16})";
  Response r = studio.handle(post("/api/run", {}, req));
  ASSERT_EQ(r.status, 202) << r.body;
  const Response second = studio.handle(post("/api/run", {}, req));
  EXPECT_EQ(second.status, 409);
  EXPECT_NE(error_of(second).find("already going"), std::string::npos) << second.body;
  studio.wait_for_run();
  const RunState s = studio.run_state();
  ASSERT_EQ(s.status, "done") << s.error << "\n" << s.log;
  ASSERT_EQ(s.stages.size(), 4u);
  for (const auto& st : s.stages) {
    EXPECT_EQ(st.exit_code, 0) << st.name;
    EXPECT_EQ(st.fraction, 1.0) << st.name;
  }
  // the log holds each command and the tools' lines, without the progress lines (they are the fractions)
  EXPECT_NE(s.log.find("$ qs-dissect ../../sphere.obj ../../egg.obj -o dissection"), std::string::npos) << s.log;
  EXPECT_NE(s.log.find("$ qs-morph remesh-L2 --path sphere,egg,sphere"), std::string::npos) << s.log;
  std::istringstream lines(s.log);
  for (std::string line; std::getline(lines, line);)
    EXPECT_FALSE(line.rfind("qs-dissect: ", 0) == 0 && !line.empty() && line.back() == '%') << line;
  const fs::path run = fx.root / "runs" / "run-1";
  for (const char* f : {"run.json", "dissection/dissection.json", "dissection/sphere.chart.ply", "remesh-L2/egg.obj",
                        "bake/sphere.glb", "morph.glb"})
    EXPECT_TRUE(fs::exists(run / f)) << f;
  for (const auto& e : fs::directory_iterator(fx.root / "runs"))
    EXPECT_EQ(e.path().filename(), "run-1") << "left behind: " << e.path();
  r = studio.handle(get("/api/runs"));
  const json runs = json::parse(r.body)["runs"];
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0]["run"]["meshes"][1], "egg.obj");
  bool has_glb = false;
  for (const auto& f : runs[0]["files"]) has_glb |= f["path"] == "runs/run-1/morph.glb";
  EXPECT_TRUE(has_glb);
  r = studio.handle(get("/api/mesh", {{"path", "runs/run-1/dissection/egg.chart.ply"}}));
  ASSERT_EQ(r.status, 200) << r.body;
  const json chart = json::parse(r.body);
  EXPECT_EQ(chart["patch"].size() * 3, chart["faces"].size());
  // the next run gets the next name
  ASSERT_EQ(studio.handle(post("/api/run", {}, R"({"meshes": ["egg.obj"], "level": 1, "bake_size": 16})")).status, 202);
  studio.wait_for_run();
  EXPECT_EQ(studio.run_state().name, "run-2");
  EXPECT_EQ(studio.run_state().stages.size(), 3u);  // one mesh: no morph
}

TEST(StudioRun, AFailedRunLeavesTheFolderAsItWas) {
  Fixture fx;
  qs::io::write_mesh(fx.root / "disk.obj", qs::shapes::open_disk(3));
  Studio studio(fx.options());
  const auto before = snapshot(fx.tmp.path);
  ASSERT_EQ(studio.handle(post("/api/run", {}, R"({"meshes": ["sphere.obj", "disk.obj"]})")).status, 202);
  studio.wait_for_run();
  const RunState s = studio.run_state();
  EXPECT_EQ(s.status, "failed");
  EXPECT_EQ(s.stages[0].exit_code, 2);
  EXPECT_NE(s.error.find("qs-dissect: invalid input error"), std::string::npos) << s.error;
  EXPECT_EQ(snapshot(fx.tmp.path), before);
  EXPECT_FALSE(fs::exists(fx.root / "runs"));
}

TEST(StudioRun, RunsAreNeverWrittenThroughALink) {
  Fixture fx;
  fs::create_directory_symlink(fx.outside, fx.root / "runs");
  Studio studio(fx.options());
  const auto before = snapshot(fx.tmp.path);
  const Response r = studio.handle(post("/api/run", {}, R"({"meshes": ["sphere.obj"]})"));
  EXPECT_EQ(r.status, 409);
  EXPECT_NE(error_of(r).find("symbolic link"), std::string::npos) << r.body;
  EXPECT_EQ(snapshot(fx.tmp.path), before);
}

TEST(StudioRun, AnotherProcessRunningInTheFolderIsRefused) {
  Fixture fx;
  Studio studio(fx.options());
  const int fd = open(fx.root.c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(flock(fd, LOCK_EX | LOCK_NB), 0);
  const Response r = studio.handle(post("/api/run", {}, R"({"meshes": ["sphere.obj"]})"));
  EXPECT_EQ(r.status, 409);
  EXPECT_NE(error_of(r).find("another qs-studio"), std::string::npos) << r.body;
  close(fd);
  EXPECT_FALSE(fs::exists(fx.root / "runs"));
}

TEST(StudioServer, HttpLimitsAndTraversal) {
  Fixture fx;
  fs::create_directories(fx.web / "node_modules/three/build");
  write_text(fx.web / "node_modules/three/build/three.module.js", std::string(200000, 'x'));
  StudioOptions sto = fx.options();
  sto.max_upload_bytes = 1u << 20;
  Studio studio(sto);
  ServerOptions so;
  so.port = 0;
  Server server(studio, so);
  const int port = server.bind();
  std::thread t([&] { server.listen(); });
  {
    // a second server on the same port fails instead of sharing it
    ServerOptions again = so;
    again.port = port;
    Server second(studio, again);
    EXPECT_THROW(second.bind(), qs::IoError);
  }
  httplib::Client cli("127.0.0.1", port);
  cli.set_connection_timeout(5);
  const auto before = snapshot(fx.tmp.path);

  auto page = cli.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  auto list = cli.Get("/api/meshes");
  ASSERT_TRUE(list);
  EXPECT_EQ(json::parse(list->body)["meshes"].size(), 1u);
  for (const char* path : {"/files/../outside/secret.txt", "/files/%2e%2e/outside/secret.txt", "/files/..%2foutside%2fsecret.txt",
                           "/files/%2Fetc%2Fpasswd", "/app/../../outside/secret.txt"}) {
    auto res = cli.Get(path);
    ASSERT_TRUE(res) << path;
    EXPECT_GE(res->status, 400) << path;
    EXPECT_LT(res->status, 500) << path;
    EXPECT_EQ(res->body.find("TOP-SECRET"), std::string::npos) << path << ": " << res->body;
  }
  // Large scripts and JSON go out as they are: Debian's cpp-httplib would brotli-compress them at
  // its slowest setting (seconds per megabyte) for a browser that accepts it.
  auto js = cli.Get("/node_modules/three/build/three.module.js", {{"Accept-Encoding", "gzip, deflate, br"}});
  ASSERT_TRUE(js);
  EXPECT_EQ(js->status, 200);
  EXPECT_FALSE(js->has_header("Content-Encoding")) << js->get_header_value("Content-Encoding");
  EXPECT_EQ(js->body.size(), 200000u);
  auto mesh = cli.Get("/api/mesh?path=sphere.obj", {{"Accept-Encoding", "gzip, deflate, br"}});
  ASSERT_TRUE(mesh);
  EXPECT_FALSE(mesh->has_header("Content-Encoding"));
  auto big = cli.Post("/api/upload?name=big.obj", std::string(3u << 20, 'v'), "application/octet-stream");
  if (big) {  // the server may also close the connection after refusing
    EXPECT_EQ(big->status, 413);
  }
  auto bad = cli.Post("/api/landmarks?name=sphere.obj", "{\"seeds\": [", "application/json");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  EXPECT_NE(bad->body.find("not valid JSON"), std::string::npos);
  server.stop();
  t.join();
  EXPECT_EQ(snapshot(fx.tmp.path), before);
}
