#pragma once
// Runs a built tool as a user would and captures its exit code and output.

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

struct RunResult {
  int exit = -1;
  std::string out;  // stdout and stderr together
};

inline RunResult run_tool(const std::string& tool, const std::string& args) {
  const std::string cmd = std::string(QS_TOOLS_DIR) + "/" + tool + " " + args + " 2>&1";
  RunResult r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(p);
  r.exit = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}
