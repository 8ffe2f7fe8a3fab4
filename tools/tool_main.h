#pragma once
// The one place where a tool turns failures into messages and exit codes:
//   0 ok, 1 usage, 2 invalid input, 3 i/o, 4 solver, 70 internal (see qs/core/error.h).

#include <CLI/CLI.hpp>
#if defined(__GLIBC__)
#include <malloc.h>
#include <unistd.h>
#endif
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <new>
#include <string>

#include "qs/core/error.h"

namespace qs::tools {

/// Blocks up to 8 MiB come from the heap, which grows 64 MiB at a time, and up to 1 GiB of freed
/// heap is kept for reuse, instead of being mapped afresh and page-faulted (zeroed) by the kernel
/// at every allocation; larger blocks (mesh-sized arrays) are mapped and given back at once, so
/// that peak memory stays about the same (figures: docs/developers.md, docs/benchmarks.md).
inline void tune_allocator() {
#if defined(__GLIBC__)
  mallopt(M_MMAP_THRESHOLD, 8 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  mallopt(M_TOP_PAD, 64 << 20);
#endif
}

/// glibc gives its heap transparent huge pages only when asked before main (the tunable
/// glibc.malloc.hugetlb, read from the environment at start-up), and the kernel gives them, where
/// its setting is "madvise", only to memory so marked. A tool therefore starts itself once more
/// with the tunable set (most page faults of a large mesh go). Not where the kernel gives huge
/// pages to all memory or to none, and not under valgrind (its preload would be lost); when the
/// restart fails the tool runs as it is.
inline void restart_with_huge_pages(char** argv) {
#if defined(__GLIBC__) && defined(__linux__)
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables && std::strstr(tunables, "glibc.malloc.hugetlb")) return;
  const char* preload = std::getenv("LD_PRELOAD");
  if (preload && std::strstr(preload, "vgpreload")) return;
  std::string mode;
  std::getline(std::ifstream("/sys/kernel/mm/transparent_hugepage/enabled"), mode);
  if (mode.find("[madvise]") == std::string::npos) return;
  const std::string value =
      tunables && *tunables ? std::string(tunables) + ":glibc.malloc.hugetlb=1" : "glibc.malloc.hugetlb=1";
  if (setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);  // returns only when it failed
  if (tunables) setenv("GLIBC_TUNABLES", tunables, 1);
  else unsetenv("GLIBC_TUNABLES");
#else
  (void)argv;
#endif
}

/// Runs `body` (which parses with `app` and does the work), mapping every exception to a
/// one-line message on stderr, prefixed with the tool's name, and a documented exit code.
template <class Body>
int run_tool(CLI::App& app, int argc, char** argv, Body&& body) {
  const std::string name = app.get_name();
  restart_with_huge_pages(argv);
  tune_allocator();
  try {
    try {
      app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
      return app.exit(e);  // prints help, returns 0
    } catch (const CLI::CallForAllHelp& e) {
      return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
      return app.exit(e);
    } catch (const CLI::ParseError& e) {
      std::cerr << name << ": " << e.what() << "\nRun '" << name << " --help' for usage.\n";
      return exit_code(ErrorCode::Usage);
    }
    return body();
  } catch (const Error& e) {
    std::cerr << name << ": " << error_name(e.code()) << " error: " << e.what() << "\n";
    return exit_code(e.code());
  } catch (const std::filesystem::filesystem_error& e) {
    // A file-system call that failed (permissions, a path under a file, a full disk): an i/o error.
    std::cerr << name << ": " << error_name(ErrorCode::Io) << " error: " << e.what() << "\n";
    return exit_code(ErrorCode::Io);
  } catch (const std::bad_alloc&) {
    std::cerr << name << ": internal error: out of memory\n";
    return exit_code(ErrorCode::Internal);
  } catch (const std::exception& e) {
    std::cerr << name << ": internal error: " << e.what() << " (please report this)\n";
    return exit_code(ErrorCode::Internal);
  }
}

}  // namespace qs::tools
