#include "qs/studio/server.h"

#include <httplib.h>
#include <sys/socket.h>

#include <fstream>
#include <sstream>

#include "qs/core/error.h"

namespace qs::studio {

struct Server::Impl {
  Studio& studio;
  ServerOptions opt;
  httplib::Server http;
  int port = -1;
  Impl(Studio& s, ServerOptions o) : studio(s), opt(std::move(o)) {}
};

namespace {

void reply(const Response& res, httplib::Response& out) {
  out.status = res.status;
  if (!res.file.empty()) {
    std::ifstream in(res.file, std::ios::binary);
    if (!in) {
      out.status = 404;
      out.set_content("{\"error\": \"cannot read the file\"}", "application/json");
      return;
    }
    std::ostringstream s;
    s << in.rdbuf();
    if (res.attachment)
      out.set_header("Content-Disposition", "attachment; filename=\"" + res.file.filename().string() + "\"");
    out.set_content(s.str(), res.content_type.c_str());
  } else {
    out.set_content(res.body, res.content_type.c_str());
  }
  out.set_header("Cache-Control", "no-store");
  out.set_header("X-Content-Type-Options", "nosniff");
}

}  // namespace

Server::Server(Studio& studio, ServerOptions options) : impl_(std::make_unique<Impl>(studio, std::move(options))) {
  auto& http = impl_->http;
  http.new_task_queue = [n = impl_->opt.threads] { return new httplib::ThreadPool(static_cast<size_t>(n)); };
  http.set_payload_max_length(impl_->opt.max_request_bytes);
  http.set_keep_alive_timeout(1);  // an idle browser connection gives its thread back soon
  // SO_REUSEADDR only: httplib's default also sets SO_REUSEPORT, which lets a second server bind
  // the same port and share its connections instead of failing.
  http.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });
  auto handler = [this](const httplib::Request& in, httplib::Response& out) {
    Request r;
    r.method = in.method;
    r.path = in.path;
    for (const auto& [k, v] : in.params) r.query.emplace(k, v);
    r.body = in.body;
    reply(impl_->studio.handle(r), out);
  };
  http.Get(".*", handler);
  http.Post(".*", handler);
  http.Put(".*", handler);
  http.Delete(".*", handler);
  http.Patch(".*", handler);
  http.set_error_handler([](const httplib::Request&, httplib::Response& out) {
    if (!out.body.empty()) return;
    std::string msg = out.status == 413 ? "request too large" : "request refused (HTTP " + std::to_string(out.status) + ")";
    out.set_content("{\"error\": \"" + msg + "\"}", "application/json");
  });
}

Server::~Server() { stop(); }

int Server::bind() {
  auto& i = *impl_;
  if (i.opt.port == 0) i.port = i.http.bind_to_any_port(i.opt.host);
  else i.port = i.http.bind_to_port(i.opt.host, i.opt.port) ? i.opt.port : -1;
  if (i.port < 0)
    throw IoError("cannot listen on " + i.opt.host + ":" + std::to_string(i.opt.port) +
                  " (in use, or not an address of this machine); choose another --port");
  return i.port;
}

void Server::listen() { impl_->http.listen_after_bind(); }

void Server::stop() {
  if (impl_ && impl_->http.is_running()) impl_->http.stop();
}

}  // namespace qs::studio
