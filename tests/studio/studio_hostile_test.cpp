// qs-studio against hostile requests and hostile surroundings: deep JSON, numbers out of range,
// names that are not UTF-8, coordinates beyond single precision, bodies larger than a route takes
// (refused from the headers, capped while streaming), uploads in the content types browsers and
// curl send, a studio stopped or killed during a run, run numbers of any length. Each case has a
// test of its own; tools are stand-in scripts where only their lifetime matters.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "qs/studio/server.h"
#include "qs/studio/studio.h"
#include "studio_requests.h"

// After Eigen (through qs/core/mesh.h): httplib pulls in <resolv.h>, whose `_res` macro breaks
// Eigen's headers.
#include <httplib.h>

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace qs::studio;
using qs::studio::test::error_of;
using qs::studio::test::get;
using qs::studio::test::post;
using namespace std::chrono_literals;

namespace {

struct Folder {
  fs::path tmp, root, web, tools;
  Folder() {
    std::string t = (fs::temp_directory_path() / "qs-studio-hostile-XXXXXX").string();
    tmp = mkdtemp(t.data());
    root = tmp / "meshes";
    web = tmp / "web";
    tools = tmp / "tools";
    fs::create_directories(root);
    fs::create_directories(web);
    fs::create_directories(tools);
    std::ofstream(web / "index.html") << "<html></html>";
    qs::io::write_mesh(root / "sphere.obj", qs::shapes::icosphere(2));
  }
  ~Folder() {
    std::error_code ec;
    fs::remove_all(tmp, ec);
  }
  /// Stand-in tools: each runs `script` (sh) with the stage's arguments.
  void fake_tools(const std::string& dissect, const std::string& others = "exit 0") {
    for (const char* t : {"qs-dissect", "qs-remesh", "qs-bake", "qs-morph"}) {
      const fs::path p = tools / t;
      std::ofstream(p) << "#!/bin/sh\n" << (std::string(t) == "qs-dissect" ? dissect : others) << "\n";
      fs::permissions(p, fs::perms::owner_all);
    }
  }
  StudioOptions options(bool real_tools = true) const {
    StudioOptions o;
    o.folder = root;
    o.web_dir = web;
    o.tools_dir = real_tools ? fs::path(QS_TOOLS_DIR) : tools;
    return o;
  }
};


std::string nested(int depth) { return std::string(depth, '[') + std::string(depth, ']'); }

/// A server on a free port, serving until destroyed.
struct Running {
  Studio studio;
  Server server;
  int port;
  std::thread thread;
  explicit Running(const StudioOptions& o, ServerOptions so = {})
      : studio(o), server(studio, (so.port = 0, so)), port(server.bind()), thread([this] { server.listen(); }) {}
  ~Running() {
    server.stop();
    thread.join();
  }
};

/// Sends raw bytes to 127.0.0.1:port and returns what comes back until the server closes the
/// connection, `until` appears, or 5 s pass. `more` (if any) is sent after the first answer bytes
/// were awaited for 200 ms: to see that the server answered without the body.
std::string raw_exchange(int port, const std::string& head, const std::string& until = "",
                         const std::string& more = "") {
  const int s = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return "connect failed";
  timeval tv{5, 0};
  setsockopt(s, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  (void)send(s, head.data(), head.size(), MSG_NOSIGNAL);
  if (!more.empty()) (void)send(s, more.data(), more.size(), MSG_NOSIGNAL);
  std::string got;
  char buf[4096];
  for (;;) {
    const ssize_t n = recv(s, buf, sizeof buf, 0);
    if (n <= 0) break;
    got.append(buf, static_cast<size_t>(n));
    if (!until.empty() && got.find(until) != std::string::npos) break;
  }
  close(s);
  return got;
}

bool process_gone(pid_t pid) {
  if (kill(pid, 0) != 0) return true;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  std::getline(stat, line);
  const size_t close_paren = line.rfind(')');
  return close_paren == std::string::npos || line.substr(close_paren + 2, 1) == "Z";  // a zombie has ended
}

bool wait_until(const std::function<bool()>& ok, std::chrono::milliseconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (ok()) return true;
    std::this_thread::sleep_for(10ms);
  }
  return ok();
}

std::vector<std::string> entries(const fs::path& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST(StudioHostile, DeeplyNestedBodiesGet400WithAShortMessage) {
  Folder f;
  Studio studio(f.options());
  const std::string deep = nested(100000);  // 200 KB
  const std::string deep_value = "{\"meshes\": " + nested(50000) + "}";
  for (const Request& r : {post("/api/run", {}, deep), post("/api/run", {}, deep_value),
                           post("/api/landmarks", {{"name", "sphere.obj"}}, "{\"seeds\": " + nested(100000) + "}"),
                           post("/api/seed-loop", {{"name", "sphere.obj"}}, deep)}) {
    const Response res = studio.handle(r);
    EXPECT_EQ(res.status, 400) << r.path;
    EXPECT_NE(error_of(res).find("nested more than"), std::string::npos) << res.body.substr(0, 300);
    EXPECT_LT(res.body.size(), 300u) << "the message echoes the request";
  }
  EXPECT_EQ(entries(f.root), std::vector<std::string>{"sphere.obj"});
}

TEST(StudioHostile, MessagesQuoteOnlyShortPrintableExcerpts) {
  Folder f;
  Studio studio(f.options());
  const std::string long_key(100000, 'k');
  for (const Request& r : {post("/api/run", {}, "{\"" + long_key + "\": 1}"),
                           post("/api/run", {}, "{\"meshes\": [\"" + long_key + ".obj\"]}"),
                           post("/api/run", {}, "{\"level\": \"" + long_key + "\"}"),
                           post("/api/run", {}, "{\"meshes\": [" + std::string(50000, '1') + "]}"),
                           post("/api/landmarks", {{"name", "sphere.obj"}}, "{\"" + long_key + "\": 1}"),
                           get("/files/" + long_key + "\x01"), get("/api/" + long_key)}) {
    const Response res = studio.handle(r);
    EXPECT_GE(res.status, 400) << r.path.substr(0, 40);
    EXPECT_LT(res.status, 500) << res.body.substr(0, 300);
    EXPECT_LT(res.body.size(), 600u) << res.body.substr(0, 300);
  }
}

TEST(StudioHostile, NumbersBeyondADoubleAre400) {
  Folder f;
  Studio studio(f.options());
  for (const Request& r :
       {post("/api/run", {}, R"({"meshes": ["sphere.obj"], "max_area": 1e400})"),
        post("/api/run", {}, R"({"meshes": ["sphere.obj"], "level": 1e400})"),
        post("/api/landmarks", {{"name", "sphere.obj"}}, R"({"seeds": [{"face": 1, "bary": [1e400, 0, 0]}]})"),
        post("/api/seed-loop", {{"name", "sphere.obj"}}, R"({"seeds": [{"face": 1e400, "bary": [1, 0, 0]}]})")}) {
    const Response res = studio.handle(r);
    EXPECT_EQ(res.status, 400) << r.path << ": " << res.body;
    EXPECT_EQ(error_of(res).find("please report"), std::string::npos) << res.body;
  }
  EXPECT_FALSE(fs::exists(f.root / "sphere.landmarks.json"));
}

TEST(StudioHostile, RunOptionsOutOfRangeAreRefusedNotWrapped) {
  Folder f;
  Studio studio(f.options());
  for (const std::string opt : {R"("level": 4294967299)", R"("level": -4294967293)", R"("bake_size": 4294967312)",
                                 R"("level": 18446744073709551615)", R"("level": 3.0)", R"("bake_size": 1e3)",
                                 R"("max_area": -0.0001)", R"("level": true)"}) {
    const Response res = studio.handle(post("/api/run", {}, "{\"meshes\": [\"sphere.obj\"], " + opt + "}"));
    EXPECT_EQ(res.status, 400) << opt << ": " << res.body;
  }
  const Response wrapped = studio.handle(post("/api/run", {}, R"({"meshes": ["sphere.obj"], "level": 4294967299})"));
  EXPECT_NE(error_of(wrapped).find("found 4294967299"), std::string::npos) << wrapped.body;
  EXPECT_FALSE(fs::exists(f.root / "runs"));
  EXPECT_EQ(studio.run_state().status, "idle");
}

TEST(StudioHostile, UploadNamesThatAreNotUtf8AreRefused) {
  Folder f;
  Studio studio(f.options());
  const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  for (const std::string& name : {std::string("\xFF.obj"), std::string("a\xC3.obj"), std::string("\xED\xA0\x80.obj"),
                                  std::string(300, 'n') + ".obj"}) {
    const Response res = studio.handle(post("/api/upload", {{"name", name}}, obj));
    EXPECT_GE(res.status, 400) << res.body;
    EXPECT_LT(res.status, 500) << res.body;
    EXPECT_TRUE(json::accept(res.body)) << res.body;
  }
  EXPECT_EQ(entries(f.root), std::vector<std::string>{"sphere.obj"}) << "nothing written, no staging left";
  // UTF-8 names are fine
  EXPECT_EQ(studio.handle(post("/api/upload", {{"name", "caf\xC3\xA9.obj"}}, obj)).status, 201);
}

TEST(StudioHostile, AFileNamedInAnotherEncodingDoesNotBreakTheListing) {
  Folder f;
  qs::io::write_mesh(f.root / "\xFF.obj", qs::shapes::icosphere(1));  // put there by other means
  Studio studio(f.options());
  const Response res = studio.handle(get("/api/meshes"));
  ASSERT_EQ(res.status, 200) << res.body;
  const json list = json::parse(res.body)["meshes"];
  ASSERT_EQ(list.size(), 2u);
  bool found = false;
  for (const auto& m : list)
    if (m["name"] == "\\xff.obj") {
      found = true;
      EXPECT_FALSE(m["accepted"].get<bool>());
      EXPECT_NE(m["summary"].get<std::string>().find("not valid UTF-8"), std::string::npos);
    }
  EXPECT_TRUE(found) << res.body;
  // and the file cannot be asked for: 4xx, never 500
  for (const Request& r : {get("/files/\xFF.obj"), get("/files/\xFFx.obj"), get("/api/mesh", {{"path", "\xFF.obj"}}),
                           get("/api/landmarks", {{"name", "\xFF.obj"}})}) {
    const Response bad = studio.handle(r);
    EXPECT_GE(bad.status, 400) << bad.body;
    EXPECT_LT(bad.status, 500) << bad.body;
    EXPECT_TRUE(json::accept(bad.body)) << bad.body;
  }
}

TEST(StudioHostile, NoExceptionTextInHeadersAndNo500ForBadPaths) {
  Folder f;
  Running s(f.options());
  for (const char* path : {"/files/%FFx.obj", "/files/%FF.obj", "/api/mesh?path=%FF.obj", "/%FF", "/files/a%00b.obj",
                           "/api/upload?name=%FF.obj"}) {
    const std::string got = raw_exchange(s.port, std::string("GET ") + path + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
    ASSERT_GT(got.size(), 12u) << path;
    const int status = std::stoi(got.substr(9, 3));
    EXPECT_GE(status, 400) << path << "\n" << got;
    EXPECT_LT(status, 500) << path << "\n" << got;
    EXPECT_EQ(got.find("EXCEPTION_WHAT"), std::string::npos) << got;
  }
}

TEST(StudioHostile, CoordinatesBeyondSinglePrecisionAreServedExactly) {
  Folder f;
  std::ofstream(f.root / "tet39.obj") << "v 1e39 0 0\nv 0 1e39 0\nv 0 0 1e39\nv 0 0 0\nf 1 2 3\nf 1 4 2\nf 2 4 3\nf 3 4 1\n";
  std::ofstream(f.root / "tet101.obj") << "v 1e101 0 0\nv 0 1 0\nv 0 0 1\nv 0 0 0\nf 1 2 3\nf 1 4 2\nf 2 4 3\nf 3 4 1\n";
  Studio studio(f.options());
  const Response mesh = studio.handle(get("/api/mesh", {{"path", "tet39.obj"}}));
  ASSERT_EQ(mesh.status, 200) << mesh.body;
  const json j = json::parse(mesh.body);
  ASSERT_EQ(j["positions"].size(), 12u);
  for (const auto& x : j["positions"]) EXPECT_TRUE(x.is_number()) << mesh.body;
  EXPECT_EQ(j["positions"][0].get<double>(), 1e39);
  EXPECT_EQ(j["positions"][4].get<double>(), 1e39);
  const json list = json::parse(studio.handle(get("/api/meshes")).body)["meshes"];
  for (const auto& m : list) {
    if (m["name"] == "tet39.obj") {
      // the tools take it; the page is told it cannot draw it
      EXPECT_TRUE(m["accepted"].get<bool>());
      bool note = false;
      for (const auto& p : m["problems"]) note |= p["kind"] == "viewer_range";
      EXPECT_TRUE(note) << m.dump();
    }
    if (m["name"] == "tet101.obj") {  // as the tools refuse it
      EXPECT_FALSE(m["accepted"].get<bool>()) << m.dump();
    }
  }
  // ordinary coordinates go out as the shortest text of the float the page draws with
  const Response sphere = studio.handle(get("/api/mesh", {{"path", "sphere.obj"}}));
  EXPECT_EQ(json::parse(sphere.body)["positions"].size(), 3u * 162);
  EXPECT_EQ(sphere.body.find("null"), std::string::npos);
}

TEST(StudioServer, BodyOverTheRouteLimitIsRefusedFromItsHeaders) {
  Folder f;
  Running s(f.options());
  // 255 MB declared, none sent: the answer comes without the body (it is never read)
  for (const std::string path : {"/api/run", "/api/landmarks?name=sphere.obj", "/api/upload?name=x.obj", "/api/meshes"}) {
    const std::string declared = path == "/api/upload?name=x.obj" ? "1073741824" : "267386880";
    const std::string method = path == "/api/meshes" ? "GET" : "POST";
    const auto t0 = std::chrono::steady_clock::now();
    const std::string got =
        raw_exchange(s.port, method + " " + path + " HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: " +
                                 declared + "\r\n\r\n{");
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s) << path;
    EXPECT_EQ(got.substr(0, 12), "HTTP/1.1 413") << path << "\n" << got;
    EXPECT_NE(got.find(declared), std::string::npos) << "the message gives the size: " << got;
  }
  // with Expect: 100-continue (curl's way for large bodies) the refusal comes instead of the 100
  const std::string got = raw_exchange(
      s.port, "POST /api/run HTTP/1.1\r\nHost: x\r\nContent-Length: 267386880\r\nExpect: 100-continue\r\n\r\n", "}");
  EXPECT_EQ(got.substr(0, 12), "HTTP/1.1 413") << got;
  EXPECT_EQ(got.find("100 Continue"), std::string::npos) << got;
  // an upload under a name it cannot take is refused before its body is read
  const std::string named = raw_exchange(
      s.port, "POST /api/upload?name=%FF.obj HTTP/1.1\r\nHost: x\r\nContent-Length: 104857600\r\n\r\nv 0 0 0\n");
  EXPECT_EQ(named.substr(0, 12), "HTTP/1.1 403") << named;
  const std::string taken = raw_exchange(
      s.port, "POST /api/upload?name=sphere.obj HTTP/1.1\r\nHost: x\r\nContent-Length: 104857600\r\n\r\nv 0 0 0\n");
  EXPECT_EQ(taken.substr(0, 12), "HTTP/1.1 409") << taken;
  // a Content-Length that is not a number
  const std::string junk = raw_exchange(s.port, "POST /api/run HTTP/1.1\r\nHost: x\r\nContent-Length: 12x\r\n\r\n");
  EXPECT_EQ(junk.substr(0, 12), "HTTP/1.1 400") << junk;
  EXPECT_EQ(entries(f.root), std::vector<std::string>{"sphere.obj"});
}

TEST(StudioServer, ChunkedBodiesAreCappedWhileTheyStream) {
  Folder f;
  StudioOptions o = f.options();
  o.max_upload_bytes = 1u << 20;
  Running s(o);
  std::string chunks;
  const std::string piece(64 * 1024, ' ');
  char size_line[32];
  std::snprintf(size_line, sizeof size_line, "%zx\r\n", piece.size());
  for (int i = 0; i < 40; ++i) chunks += size_line + piece + "\r\n";  // 2.5 MiB, more than 1 MiB
  chunks += "0\r\n\r\n";
  for (const std::string path : {"/api/run", "/api/upload?name=big.obj"}) {
    const std::string got =
        raw_exchange(s.port, "POST " + path + " HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n", "", chunks);
    EXPECT_EQ(got.substr(0, 12), "HTTP/1.1 413") << path << "\n" << got.substr(0, 400);
  }
  EXPECT_EQ(entries(f.root), std::vector<std::string>{"sphere.obj"}) << "no upload left behind";
  // a small chunked JSON body is read as usual
  const std::string body = R"({"meshes": ["none.obj"]})";
  char n[16];
  std::snprintf(n, sizeof n, "%zx", body.size());
  const std::string ok = raw_exchange(s.port, "POST /api/run HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\nConnection: close\r\n\r\n" +
                                                  std::string(n) + "\r\n" + body + "\r\n0\r\n\r\n");
  EXPECT_EQ(ok.substr(0, 12), "HTTP/1.1 404") << ok;
}

TEST(StudioServer, UploadsStreamInEveryContentTypeBrowsersAndCurlSend) {
  Folder f;
  Running s(f.options());
  std::ostringstream obj;
  qs::io::write_mesh(f.tmp / "big.obj", qs::shapes::icosphere(4));  // about 200 KB: more than 8 KB
  {
    std::ifstream in(f.tmp / "big.obj", std::ios::binary);
    obj << in.rdbuf();
  }
  const std::string mesh = obj.str();
  ASSERT_GT(mesh.size(), 100000u);
  httplib::Client cli("127.0.0.1", s.port);
  for (const std::string type : {"application/x-www-form-urlencoded", "application/octet-stream", "model/obj", ""}) {
    const std::string name = "up" + std::to_string(type.size()) + ".obj";
    auto res = cli.Post(("/api/upload?name=" + name).c_str(), mesh, type.c_str());
    ASSERT_TRUE(res) << type;
    EXPECT_EQ(res->status, 201) << type << ": " << res->body;
    EXPECT_EQ(fs::file_size(f.root / name), mesh.size()) << type;
  }
  // multipart/form-data (curl -F, an HTML form): the file's own name when ?name= is absent
  httplib::MultipartFormDataItems items = {{"file", mesh, "formed.obj", "application/octet-stream"}};
  auto res = cli.Post("/api/upload", items);
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 201) << res->body;
  EXPECT_EQ(fs::file_size(f.root / "formed.obj"), mesh.size());
  items.push_back({"second", "x", "second.obj", "text/plain"});
  res = cli.Post("/api/upload?name=two.obj", items);
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 400) << res->body;
  EXPECT_FALSE(fs::exists(f.root / "two.obj"));
  for (const auto& e : entries(f.root)) EXPECT_NE(e.rfind(".upload-", 0), 0u) << "left behind: " << e;
}

TEST(StudioServer, FilesAreServedWholeAndInRanges) {
  Folder f;
  std::string big(3u << 20, '\0');
  for (size_t i = 0; i < big.size(); ++i) big[i] = static_cast<char>((i * 7919) >> 3);
  std::ofstream(f.root / "data.bin", std::ios::binary) << big;
  Running s(f.options());
  httplib::Client cli("127.0.0.1", s.port);
  auto whole = cli.Get("/files/data.bin");
  ASSERT_TRUE(whole);
  EXPECT_EQ(whole->status, 200);
  EXPECT_TRUE(whole->body == big);
  auto part = cli.Get("/files/data.bin", {{"Range", "bytes=1000000-1000099"}});
  ASSERT_TRUE(part);
  EXPECT_EQ(part->status, 206);
  EXPECT_TRUE(part->body == big.substr(1000000, 100));
  std::ofstream(f.root / "empty.txt");
  auto empty = cli.Get("/files/empty.txt");
  ASSERT_TRUE(empty);
  EXPECT_EQ(empty->status, 200);
  EXPECT_TRUE(empty->body.empty());
}

TEST(StudioRun, StoppingTheStudioStopsItsTool) {
  Folder f;
  f.fake_tools("echo $$ > '" + (f.tmp / "pid").string() + "'; exec sleep 30");
  Studio studio(f.options(false));
  ASSERT_EQ(studio.handle(post("/api/run", {}, R"({"meshes": ["sphere.obj"]})")).status, 202);
  ASSERT_TRUE(wait_until([&] { return fs::exists(f.tmp / "pid") && fs::file_size(f.tmp / "pid") > 0; }, 5s));
  pid_t tool = 0;
  std::ifstream(f.tmp / "pid") >> tool;
  ASSERT_GT(tool, 0);
  const auto t0 = std::chrono::steady_clock::now();
  studio.stop_run();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 3s);
  EXPECT_TRUE(process_gone(tool));
  EXPECT_EQ(studio.run_state().status, "failed");
  EXPECT_NE(studio.run_state().error.find("stopped"), std::string::npos) << studio.run_state().error;
  EXPECT_TRUE(entries(f.root / "runs").empty()) << "staging left behind";
}

TEST(StudioRun, CancelStopsTheToolAndWhatItStartedWithin2sLeavingNothing) {
  Folder f;
  // a tool that starts a helper of its own, writes into the run's folder, then waits
  f.fake_tools("sleep 30 & echo $! > '" + (f.tmp / "child").string() + "'; mkdir dissection; echo x > dissection/half; echo $$ > '" +
               (f.tmp / "pid").string() + "'; wait");
  Studio studio(f.options(false));
  const Request start = post("/api/run", {}, R"({"meshes": ["sphere.obj"]})");
  EXPECT_EQ(studio.handle(post("/api/run/cancel", {}, "")).status, 409);  // nothing to cancel
  ASSERT_EQ(studio.handle(start).status, 202);
  ASSERT_TRUE(wait_until([&] { return fs::exists(f.tmp / "pid") && fs::file_size(f.tmp / "pid") > 0; }, 5s));
  pid_t tool = 0, child = 0;
  std::ifstream(f.tmp / "pid") >> tool;
  std::ifstream(f.tmp / "child") >> child;
  ASSERT_GT(tool, 0);
  ASSERT_GT(child, 0);
  const auto t0 = std::chrono::steady_clock::now();
  const Response r = studio.handle(post("/api/run/cancel", {}, ""));
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 2s);
  ASSERT_EQ(r.status, 200) << r.body;
  const json s = json::parse(r.body);
  EXPECT_EQ(s["status"], "cancelled");
  EXPECT_NE(s["error"].get<std::string>().find("cancelled"), std::string::npos) << r.body;
  EXPECT_TRUE(wait_until([&] { return process_gone(tool) && process_gone(child); }, 1s)) << "the tool or its helper outlived the cancel";
  if (!process_gone(child)) kill(child, SIGKILL);
  EXPECT_TRUE(entries(f.root / "runs").empty()) << "staging left behind";
  EXPECT_FALSE(fs::exists(f.root / "runs" / "run-1"));
}

TEST(StudioRun, OverallProgressNeverDecreasesAndNamesThePhase) {
  Folder f;
  // per-phase fractions that go back and forth, as qs-dissect's do
  f.fake_tools("for p in 'seed loops 25' 'seed loops 100' 'quinary subdivision 1' 'quinary subdivision 19' 'leaf repairs 0' "
               "'quinary subdivision 13' 'refine maps 0' 'refine maps 25'; do echo \"qs-dissect: $p%\" >&2; sleep 0.05; done",
               "sleep 0.1");
  Studio studio(f.options(false));
  ASSERT_EQ(studio.handle(post("/api/run", {}, R"({"meshes": ["sphere.obj"]})")).status, 202);
  std::vector<double> seen;
  std::set<std::string> phases;
  for (;;) {
    const json s = json::parse(studio.handle(get("/api/run")).body);
    seen.push_back(s["progress"].get<double>());
    phases.insert(s["phase"].get<std::string>());
    if (s["status"] != "running") {
      EXPECT_EQ(s["status"], "done") << s["error"];
      EXPECT_EQ(s["eta_s"].get<double>(), 0);
      break;
    }
    std::this_thread::sleep_for(10ms);
  }
  studio.wait_for_run();
  ASSERT_GE(seen.size(), 5u);
  for (size_t i = 1; i < seen.size(); ++i) EXPECT_GE(seen[i], seen[i - 1]) << "at " << i;
  EXPECT_EQ(seen.back(), 1.0);
  EXPECT_TRUE(phases.count("dissect: quinary subdivision")) << "phases seen: " << phases.size();
}

TEST(StudioRun, RunsAreDeletedAndArchivedOnlyByTheirOwnNames) {
  Folder f;
  f.fake_tools("mkdir dissection && echo report > dissection/dissection.json", "mkdir -p out && echo x > out/$$.txt");
  Studio studio(f.options(false));
  ASSERT_EQ(studio.handle(post("/api/run", {}, R"({"meshes": ["sphere.obj"]})")).status, 202);
  studio.wait_for_run();
  ASSERT_EQ(studio.run_state().status, "done") << studio.run_state().error;
  ASSERT_TRUE(fs::exists(f.root / "runs" / "run-1" / "run.json"));
  // names that are not run-N, or lead elsewhere, are refused and nothing is removed
  fs::create_directories(f.tmp / "victim");
  std::ofstream(f.tmp / "victim" / "keep.txt") << "keep";
  fs::create_directory_symlink(f.tmp / "victim", f.root / "runs" / "run-7");
  for (const char* bad : {"../victim", "run-1/..", "runs", "", "run-1/dissection", "run-7"}) {
    const Response r = studio.handle(Request{"DELETE", "/api/runs", {{"name", bad}}, ""});
    EXPECT_GE(r.status, 400) << bad;
    EXPECT_LT(r.status, 500) << bad << ": " << r.body;
    const Response a = studio.handle(get("/api/run-archive", {{"name", bad}}));
    EXPECT_GE(a.status, 400) << bad;
    EXPECT_TRUE(a.archive.empty()) << bad;
  }
  EXPECT_TRUE(fs::exists(f.tmp / "victim" / "keep.txt"));
  for (const char* bad : {"../meshes/sphere.obj", "/etc/passwd.obj", "sub/sphere.obj", "nothere.obj", "notes.txt"}) {
    const Response r = studio.handle(Request{"DELETE", "/api/meshes", {{"name", bad}}, ""});
    EXPECT_GE(r.status, 400) << bad;
    EXPECT_LT(r.status, 500) << bad << ": " << r.body;
  }
  EXPECT_TRUE(fs::exists(f.root / "sphere.obj"));
  // the run as a tar: every file under run-1/, readable by tar
  const Response a = studio.handle(get("/api/run-archive", {{"name", "run-1"}}));
  ASSERT_EQ(a.status, 200) << a.body;
  EXPECT_EQ(a.download_name, "run-1.tar");
  const TarLayout tar(a.archive);
  std::string bytes(tar.size(), '\0');
  for (size_t at = 0; at < bytes.size();) {
    const size_t n = tar.read(at, bytes.data() + at, 1000);  // in pieces, as the server sends it
    ASSERT_GT(n, 0u) << at;
    at += n;
  }
  EXPECT_EQ(tar.read(bytes.size(), bytes.data(), 1), 0u);
  std::ofstream(f.tmp / "run.tar", std::ios::binary) << bytes;
  const std::string list = f.tmp / "list.txt";
  ASSERT_EQ(std::system(("tar -tf '" + (f.tmp / "run.tar").string() + "' > '" + list + "'").c_str()), 0);
  std::ifstream in(list);
  std::set<std::string> names;
  for (std::string line; std::getline(in, line);) names.insert(line);
  EXPECT_TRUE(names.count("run-1/run.json") && names.count("run-1/dissection/dissection.json")) << bytes.size();
  // a name over 100 bytes (GNU long name) comes back whole
  const std::string long_name = "run-1/" + std::string(150, 'n') + ".txt";
  const TarLayout long_tar({{long_name, f.root / "sphere.obj"}});
  std::string lb(long_tar.size(), '\0');
  for (size_t at = 0; at < lb.size();) {
    const size_t n = long_tar.read(at, lb.data() + at, lb.size() - at);
    ASSERT_GT(n, 0u) << at;
    at += n;
  }
  std::ofstream(f.tmp / "long.tar", std::ios::binary) << lb;
  ASSERT_EQ(std::system(("tar -xOf '" + (f.tmp / "long.tar").string() + "' '" + long_name + "' | cmp -s - '" +
                         (f.root / "sphere.obj").string() + "'").c_str()),
            0);
  // deleted by its name
  const Response d = studio.handle(Request{"DELETE", "/api/runs", {{"name", "run-1"}}, ""});
  EXPECT_EQ(d.status, 200) << d.body;
  EXPECT_FALSE(fs::exists(f.root / "runs" / "run-1"));
  EXPECT_TRUE(fs::exists(f.tmp / "victim" / "keep.txt"));
  const Response m = studio.handle(Request{"DELETE", "/api/meshes", {{"name", "sphere.obj"}}, ""});
  EXPECT_EQ(m.status, 200) << m.body;
  EXPECT_FALSE(fs::exists(f.root / "sphere.obj"));
}

TEST(StudioRun, ResultsAreJudgedFromTheToolsReports) {
  Folder f;
  const fs::path run = f.tmp / "run";
  fs::create_directories(run / "dissection");
  fs::create_directories(run / "remesh-L3");
  fs::create_directories(run / "bake");
  // nothing known to be wrong: no warnings
  EXPECT_TRUE(judge_run(run, "remesh-L3", "").empty());
  std::ofstream(run / "dissection" / "dissection.json") << R"({"options": {"tau": 3}, "base_domain": {"patches": )"
      << json(std::vector<std::string>(130, "p")).dump()
      << R"(}, "meshes": [{"file": "a.obj", "max_stretch": 12.5, "patches_over_tau": 2,
           "patches": [{"faces": 80, "stretch": 1.2, "flipped_faces": 0}, {"faces": 20, "stretch": 12.5, "flipped_faces": 3, "stop_reason": "max_depth"}]},
          {"file": "b.obj", "max_stretch": 2.0, "patches_over_tau": 0, "patches": [{"faces": 100, "stretch": 2.0, "flipped_faces": 0}]}]})";
  std::ofstream(run / "remesh-L3" / "remesh.json")
      << R"({"meshes": [{"output": "a.obj", "angles": {"min_deg": 0.01, "under_5_deg": 0.05}}, {"output": "b.obj", "angles": {"min_deg": 20, "under_5_deg": 0}}]})";
  std::ofstream(run / "bake" / "bake.json")
      << R"({"meshes": [{"glb": "a.glb", "shading": {"mean_deg_with_map": 15.2}}, {"glb": "b.glb", "shading": {"mean_deg_with_map": 0.3}}]})";
  const auto w = judge_run(run, "remesh-L3", "$ qs-dissect a b\nqs-dissect: warning: no seeds given; automatic seeds\nnot a warning\n");
  std::string all;
  for (const auto& x : w) all += x + "\n";
  EXPECT_EQ(w.size(), 6u) << all;
  for (const char* part : {"qs-dissect: no seeds given", "a: 2 patches left over the stretch limit tau 3, holding 20% of the triangles, largest stretch 12.5",
                           "a: 3 folded triangles", "130 patches", "a: thin triangles in the remesh (smallest angle 0.01 deg",
                           "a: the normal map misses the original's shading by 15.2 deg"})
    EXPECT_NE(all.find(part), std::string::npos) << part << " in\n" << all;
  EXPECT_EQ(all.find("b:"), std::string::npos) << all;
  // unreadable reports are not faults of the result
  std::ofstream(run / "bake" / "bake.json") << "{not json";
  EXPECT_EQ(judge_run(run, "remesh-L3", "").size(), 4u);
}

TEST(StudioRun, AKilledStudioLeavesNoToolAndItsStagingIsCleanedNextTime) {
  Folder f;
  f.fake_tools("echo $$ > '" + (f.tmp / "pid").string() + "'; exec sleep 30");
  const pid_t studio_process = fork();
  if (studio_process == 0) {
    Studio studio(f.options(false));
    studio.handle(post("/api/run", {}, R"({"meshes": ["sphere.obj"]})"));
    pause();
    _exit(0);
  }
  ASSERT_TRUE(wait_until([&] { return fs::exists(f.tmp / "pid") && fs::file_size(f.tmp / "pid") > 0; }, 5s));
  pid_t tool = 0;
  std::ifstream(f.tmp / "pid") >> tool;
  ASSERT_GT(tool, 0);
  ASSERT_EQ(entries(f.root / "runs"), std::vector<std::string>{".run-1.partial"});
  kill(studio_process, SIGKILL);
  waitpid(studio_process, nullptr, 0);
  EXPECT_TRUE(wait_until([&] { return process_gone(tool); }, 2s)) << "the tool outlived the studio";
  if (!process_gone(tool)) kill(tool, SIGKILL);
  // the next studio in the folder removes the dead run's staging
  Studio next(f.options(false));
  EXPECT_TRUE(entries(f.root / "runs").empty());
}

TEST(StudioRun, StagingInUseIsNotRemoved) {
  Folder f;
  fs::create_directories(f.root / "runs" / ".run-3.partial");
  std::ofstream(f.root / ".upload-1-1.obj") << "v";
  Studio first(f.options());
  EXPECT_TRUE(entries(f.root / "runs").empty());
  EXPECT_FALSE(fs::exists(f.root / ".upload-1-1.obj"));
  // an upload being written (locked) and a run going in another process (folder lock) stay
  auto upload = first.new_upload_file(".obj");
  upload.write("v", 1);
  fs::create_directories(f.root / "runs" / ".run-4.partial");
  const int lock = open(f.root.c_str(), O_RDONLY | O_DIRECTORY);
  ASSERT_EQ(flock(lock, LOCK_EX | LOCK_NB), 0);
  Studio second(f.options());
  EXPECT_TRUE(fs::exists(upload.path()));
  EXPECT_TRUE(fs::exists(f.root / "runs" / ".run-4.partial"));
  close(lock);
}

TEST(StudioRun, RunNumbersHaveNoLimitAndNeverCollide) {
  EXPECT_EQ(next_run_name({}), "run-1");
  EXPECT_EQ(next_run_name({"run-99999999", "run-7", "notes.txt", ".run-100000000.partial"}), "run-100000000");
  EXPECT_EQ(next_run_name({"run-99999999999999999999999"}), "run-100000000000000000000000");
  EXPECT_EQ(next_run_name({"run-0009", "run-", "run-1x"}), "run-10");
  EXPECT_EQ(run_number("run-0042"), "42");
  EXPECT_EQ(run_number("run-"), "");
  EXPECT_EQ(run_number("run-4a"), "");

  Folder f;
  // qs-dissect makes the name this run would take, as a person could meanwhile: the run moves on
  f.fake_tools("mkdir -p ../run-100000000/x", "exit 0");
  fs::create_directories(f.root / "runs" / "run-99999999");
  Studio studio(f.options(false));
  ASSERT_EQ(studio.handle(post("/api/run", {}, R"({"meshes": ["sphere.obj"]})")).status, 202);
  studio.wait_for_run();
  ASSERT_EQ(studio.run_state().status, "done") << studio.run_state().error;
  EXPECT_EQ(studio.run_state().name, "run-100000001");
  const json runs = json::parse(studio.handle(get("/api/runs")).body)["runs"];
  std::vector<std::string> names;
  for (const auto& r : runs) names.push_back(r["name"]);
  EXPECT_EQ(names, (std::vector<std::string>{"run-99999999", "run-100000000", "run-100000001"}));
  EXPECT_EQ(runs[2]["run"]["name"], "run-100000001");
  // and the next one after that
  ASSERT_EQ(studio.handle(post("/api/run", {}, R"({"meshes": ["sphere.obj"]})")).status, 202);
  studio.wait_for_run();
  EXPECT_EQ(studio.run_state().name, "run-100000002") << studio.run_state().error;
}
