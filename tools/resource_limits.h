#pragma once
// Up-front resource checks shared by the tools: a request is estimated before any work, and
// refused with the figure (exit 1) when it exceeds a documented limit that a flag can raise.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <string>

#include "qs/core/error.h"

namespace qs::tools {

/// Default of --max-memory, in GiB: the estimated peak memory a tool may plan for.
inline constexpr double kDefaultMaxMemoryGiB = 8.0;

inline std::string gib_text(double bytes) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.3g GiB", bytes / (1024.0 * 1024.0 * 1024.0));
  return buf;
}

/// Adds --max-memory GIB to `app` (bound to `gib`).
inline void add_max_memory_option(CLI::App& app, double& gib) {
  app.add_option("--max-memory", gib,
                 "Refuse up front a request whose estimated memory exceeds this many GiB (the estimate is printed)")
      ->capture_default_str()
      ->check(CLI::Range(0.001, 1e6));
}

/// \throws UsageError when `bytes` (the estimate for `what`) exceeds `limit_gib`.
inline void check_memory(double bytes, double limit_gib, const std::string& what) {
  if (!(bytes <= limit_gib * 1024.0 * 1024.0 * 1024.0))
    throw UsageError(what + " needs about " + gib_text(bytes) + " of memory, more than --max-memory " +
                     gib_text(limit_gib * 1024.0 * 1024.0 * 1024.0) +
                     "; ask for less, or raise --max-memory if the machine has it");
}

}  // namespace qs::tools
