// libFuzzer target: qs-studio's request checks (qs::studio::check_request), the pure part of the
// server that turns a method, path, query and body into a validated request. Input: the method,
// the path and the query ("k=v&k=v", not decoded) on the first three lines, the body after them.
// Every refusal must be a qs::Error with a short, printable message; anything else aborts.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/studio/studio.h"

namespace {

std::string_view next_line(std::string_view& text) {
  const size_t nl = text.find('\n');
  const std::string_view line = text.substr(0, nl);
  text = nl == std::string_view::npos ? std::string_view() : text.substr(nl + 1);
  return line;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const qs::studio::StudioOptions options = [] {
    qs::studio::StudioOptions o;
    o.max_json_bytes = 4096;  // small limits, so that the fuzzer reaches the 413s too
    o.max_upload_bytes = 8192;
    return o;
  }();
  std::string_view text(reinterpret_cast<const char*>(data), size);
  qs::studio::Request r;
  r.method = std::string(next_line(text));
  r.path = std::string(next_line(text));
  std::string_view query = next_line(text);
  while (!query.empty()) {
    const size_t amp = query.find('&');
    const std::string_view pair = query.substr(0, amp);
    const size_t eq = pair.find('=');
    r.query.emplace(std::string(pair.substr(0, eq)), eq == std::string_view::npos ? "" : std::string(pair.substr(eq + 1)));
    query = amp == std::string_view::npos ? std::string_view() : query.substr(amp + 1);
  }
  r.body = std::string(text);
  try {
    const qs::studio::CheckedRequest c = qs::studio::check_request(r, options);
    // What passed is what the handlers rely on: names are clean UTF-8.
    if (!qs::json_strict::is_clean_text(c.name)) std::abort();
    for (const auto& m : c.run.meshes)
      if (!qs::json_strict::is_clean_text(m)) std::abort();
  } catch (const qs::Error& e) {
    const std::string_view what = e.what();
    if (what.size() > 1000 || !qs::json_strict::is_clean_text(what)) std::abort();
  }
  return 0;
}
