#pragma once
// Requests to the studio's handler as the server would build them, and the error a response carries.

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

#include "qs/studio/studio.h"

namespace qs::studio::test {

inline Request get(const std::string& path, std::map<std::string, std::string> query = {}) {
  return Request{"GET", path, std::move(query), "", {}, {}};
}
inline Request post(const std::string& path, std::map<std::string, std::string> query, std::string body) {
  return Request{"POST", path, std::move(query), std::move(body), {}, {}};
}
/// The response's "error" text ("" when there is none or the body is not JSON).
inline std::string error_of(const Response& r) {
  try {
    return nlohmann::json::parse(r.body).value("error", std::string());
  } catch (const nlohmann::json::exception&) {
    return "";
  }
}

}  // namespace qs::studio::test
