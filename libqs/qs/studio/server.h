#pragma once
// The HTTP side of qs-studio: cpp-httplib (kept out of this header) in front of a Studio.

#include <memory>
#include <string>

#include "qs/studio/studio.h"

namespace qs::studio {

struct ServerOptions {
  std::string host = "127.0.0.1";  ///< listen address; anything else is reachable from the network
  int port = 8420;                 ///< 0: any free port
  /// A cap on any body httplib would read by itself; each route's own limit (Studio::body_limit)
  /// is checked from the headers first and enforced while the body streams in.
  size_t max_request_bytes = 256u << 20;
  /// Worker threads. A browser keeps up to 6 connections open (keep-alive) and each holds a
  /// thread while open, so fewer threads than that stall page loads.
  int threads = 16;
};

class Server {
 public:
  Server(Studio& studio, ServerOptions options);
  ~Server();
  /// Binds the socket; returns the port. \throws IoError when the address cannot be bound.
  int bind();
  /// Serves until stop() (blocking).
  void listen();
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace qs::studio
