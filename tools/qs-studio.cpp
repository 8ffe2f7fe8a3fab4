// qs-studio: a local web page to pick landmarks, run the pipeline and look at the results.
// Serves FOLDER's meshes and the page (web/studio) on 127.0.0.1; runs qs-dissect, qs-remesh,
// qs-bake and qs-morph (found beside this program) as subprocesses; writes only inside FOLDER.
//
// Exit codes: 0 stopped (Ctrl-C or SIGTERM: a run in progress is stopped, its tool ended and its
// staging removed), 1 usage, 2 FOLDER is not a folder, 3 i/o (FOLDER missing, the
// port cannot be bound), 70 internal error.

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <iostream>
#include <thread>

#include "qs/studio/server.h"
#include "qs/studio/studio.h"
#include "tool_main.h"

namespace fs = std::filesystem;

#ifndef QS_STUDIO_WEB_DIR
#define QS_STUDIO_WEB_DIR "web/studio"
#endif

namespace {

fs::path own_folder(const char* argv0) {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) return exe.parent_path();
  return fs::absolute(argv0).parent_path();
}

bool is_loopback(const std::string& host) {
  return host == "127.0.0.1" || host == "localhost" || host == "::1" || host.rfind("127.", 0) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"A local web page for qs: list and check the meshes of FOLDER, place seeds and features by\n"
               "clicking, run dissect/remesh/bake/morph and look at the results. Open the address it prints.\n"
               "Writes only inside FOLDER: <stem>.landmarks.json, uploaded meshes, runs/run-N/.\n"
               "Exit codes: 0 stopped, 1 usage, 2 invalid input, 3 i/o, 70 internal.",
               "qs-studio"};
  // The page: installed beside the tools (share/qs/studio), else the source tree's.
  std::string folder = ".", host = "127.0.0.1", web_dir = QS_STUDIO_WEB_DIR, tools_dir;
  if (const fs::path installed = own_folder(argv[0]) / "../share/qs/studio"; fs::exists(installed / "index.html"))
    web_dir = fs::weakly_canonical(installed).string();
  int port = 8420;
  bool quiet = false;
  app.add_option("folder", folder, "The folder of meshes (.obj .off .ply .stl) to work on")->capture_default_str();
  app.add_option("--port", port, "TCP port (0: any free port)")->capture_default_str()->check(CLI::Range(0, 65535));
  app.add_option("--host", host,
                 "Address to listen on; anything but 127.0.0.1 lets other machines reach the page and run tools")
      ->capture_default_str();
  app.add_option("--web", web_dir, "The page's folder (index.html, app/, node_modules/three)")->capture_default_str();
  app.add_option("--tools", tools_dir, "Folder of qs-dissect, qs-remesh, qs-bake, qs-morph (default: beside qs-studio)");
  app.add_flag("-q,--quiet", quiet, "Print only the address and errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    qs::studio::StudioOptions so;
    so.folder = folder;
    so.web_dir = web_dir;
    so.tools_dir = tools_dir.empty() ? own_folder(argv[0]) : fs::path(tools_dir);
    if (!fs::exists(fs::path(web_dir) / "index.html"))
      throw qs::IoError("the page is not in '" + web_dir + "' (no index.html); pass --web DIR");
    qs::studio::Studio studio(so);
    qs::studio::ServerOptions opt;
    opt.host = host;
    opt.port = port;
    opt.max_request_bytes = so.max_upload_bytes;

    // SIGINT/SIGTERM end the server from a thread of their own (httplib's stop is not signal-safe).
    // (A shell starting us in the background may have set them to be ignored: a blocked, ignored
    // signal is discarded, and sigwait would never see it.)
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
    sigset_t sigs;
    sigemptyset(&sigs);
    sigaddset(&sigs, SIGINT);
    sigaddset(&sigs, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &sigs, nullptr);

    qs::studio::Server server(studio, opt);
    const int bound = server.bind();
    if (!is_loopback(host))
      std::cerr << "qs-studio: warning: listening on " << host
                << ": other machines can reach the page, read the folder's meshes and run tools; use the "
                   "default 127.0.0.1 unless you mean it\n";
    const std::string shown = host.find(':') != std::string::npos ? "[" + host + "]" : host;
    std::cout << "qs-studio: serving " << studio.folder().string() << "\n"
              << "open http://" << (host == "0.0.0.0" ? std::string("127.0.0.1") : shown) << ":" << bound << "/\n"
              << std::flush;
    if (!fs::exists(fs::path(web_dir) / "node_modules/three/build/three.module.js"))
      std::cerr << "qs-studio: warning: three.js is missing from " << web_dir
                << "/node_modules; run scripts/setup.sh (the page will say so)\n";
    std::atomic<bool> stopping = false;
    std::thread waiter([&] {
      int sig = 0;
      sigwait(&sigs, &sig);
      stopping = true;
      if (!quiet) std::cout << "qs-studio: stopping\n" << std::flush;
      server.stop();
    });
    server.listen();
    if (!stopping) pthread_kill(waiter.native_handle(), SIGTERM);  // listen() ended on its own
    waiter.join();
    // A run in progress is stopped: its tool gets SIGTERM (cleaning up its own output), the run's
    // staging folder is removed. (Tools also get SIGTERM if this process is killed outright.)
    studio.stop_run();
    return 0;
  });
}
