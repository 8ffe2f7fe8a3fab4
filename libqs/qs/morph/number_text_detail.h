#pragma once
// Numbers written as the shortest text that reads back exactly (std::to_chars), appended to a
// string: the OBJ frames' coordinates and indices.
#include <charconv>
#include <string>

namespace qs::morph::detail {

template <class T>
void append_number(std::string& out, T v) {
  char buf[32];
  out.append(buf, std::to_chars(buf, buf + sizeof buf, v).ptr);
}

}  // namespace qs::morph::detail
