#include "qs/studio/server.h"

#include <fcntl.h>
#include <httplib.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <memory>
#include <optional>

#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/studio/paths.h"

// <resolv.h> (through httplib.h) defines _res, a parameter name of Eigen's headers: in a unity
// build the files after this one would not compile.
#undef _res

namespace qs::studio {

struct Server::Impl {
  Studio& studio;
  ServerOptions opt;
  httplib::Server http;
  int port = -1;
  Impl(Studio& s, ServerOptions o) : studio(s), opt(std::move(o)) {}
};

namespace {

/// {"error": message} with the message escaped for JSON (printable() leaves no control bytes;
/// quotes and backslashes are escaped here).
std::string error_body(const std::string& message) {
  std::string m = json_strict::printable(message, 400), out;
  for (char c : m) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return "{\"error\": \"" + out + "\"}";
}

/// Answers `status` with `json_body` and closes the connection after the answer: the request's body (too large,
/// or cut off) is not read, so the connection cannot carry another request. httplib closes a
/// connection whose response content provider reports failure; this one writes the whole answer
/// first.
void close_with(httplib::Response& out, int status, const std::string& json_body) {
  out.status = status;
  out.set_header("Connection", "close");
  auto body = std::make_shared<std::string>(json_body);
  out.set_content_provider(body->size(), "application/json", [body](size_t offset, size_t length, httplib::DataSink& sink) {
    sink.write(body->data() + offset, length);
    return false;
  });
}

void refuse_and_close(httplib::Response& out, int status, const std::string& message) {
  close_with(out, status, error_body(message));
}

/// The declared body length: nullopt when there is none, SIZE_MAX when it is not a number or too
/// large to represent.
std::optional<size_t> content_length(const httplib::Request& in) {
  if (!in.has_header("Content-Length")) return std::nullopt;
  const std::string v = in.get_header_value("Content-Length");
  if (v.empty() || v.size() > 19) return SIZE_MAX;
  size_t n = 0;
  for (char c : v) {
    if (c < '0' || c > '9') return SIZE_MAX;
    n = n * 10 + static_cast<size_t>(c - '0');
  }
  return n;
}

bool is_chunked(const httplib::Request& in) {
  return in.get_header_value("Transfer-Encoding").find("chunked") != std::string::npos;
}

/// The refusal of a body by its headers alone, or "" when it may be read.
std::string refuse_by_headers(const httplib::Request& in, const BodyLimit& limit, int& status) {
  const auto length = content_length(in);
  status = 413;
  if (length && *length == SIZE_MAX) {
    status = 400;
    return "the Content-Length header is not a byte count: '" + json_strict::printable(in.get_header_value("Content-Length"), 40) + "'";
  }
  if (length && *length > limit.bytes)
    return limit.bytes == 0 ? "a " + in.method + " request takes no body (Content-Length " + std::to_string(*length) + ")"
                            : "request body of " + std::to_string(*length) + " bytes; at most " +
                                  std::to_string(limit.bytes) + " are accepted here";
  if (!length && is_chunked(in) && limit.bytes == 0) return "a " + in.method + " request takes no body";
  return "";
}

void reply(const Response& res, httplib::Response& out) {
  out.status = res.status;
  out.set_header("Cache-Control", "no-store");
  out.set_header("X-Content-Type-Options", "nosniff");
  if (!res.archive.empty()) {
    // A tar of the listed files, laid out up front and sent in pieces straight from the disk.
    std::shared_ptr<const TarLayout> tar;
    try {
      tar = std::make_shared<const TarLayout>(res.archive);
    } catch (const Error& e) {
      out.status = 404;
      out.set_content(error_body(e.what()), "application/json");
      return;
    }
    out.set_header("Content-Disposition",
                   "attachment; filename=\"" + json_strict::printable(res.download_name, 200) + "\"");
    out.set_content_provider(tar->size(), "application/x-tar", [tar](size_t offset, size_t length, httplib::DataSink& sink) {
      char buf[1 << 16];
      const size_t n = tar->read(offset, buf, std::min(length, sizeof buf));
      if (n == 0) return false;  // a file shrank meanwhile: the connection is closed
      return sink.write(buf, n);
    });
    return;
  }
  if (res.file.empty()) {
    out.set_content(res.body, res.content_type);
    return;
  }
  // Files are sent in pieces straight from the disk, never held whole in memory.
  const int fd = open(res.file.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    if (fd >= 0) close(fd);
    out.status = 404;
    out.set_content(error_body("cannot read the file"), "application/json");
    return;
  }
  if (res.attachment)
    out.set_header("Content-Disposition",
                   "attachment; filename=\"" + json_strict::printable(res.file.filename().string(), 200) + "\"");
  auto file = std::shared_ptr<int>(new int(fd), [](int* f) {
    close(*f);
    delete f;
  });
  const auto size = static_cast<size_t>(st.st_size);
  if (size == 0) {
    out.set_content("", res.content_type);
    return;
  }
  if (res.status == 200) out.status = -1;  // httplib answers 206 to a Range request, 200 otherwise
  out.set_content_provider(size, res.content_type, [file](size_t offset, size_t length, httplib::DataSink& sink) {
    char buf[1 << 16];
    const ssize_t n = pread(*file, buf, std::min(length, sizeof buf), static_cast<off_t>(offset));
    if (n <= 0) return false;  // the file shrank meanwhile: the connection is closed
    return sink.write(buf, static_cast<size_t>(n));
  });
}

Request studio_request(const httplib::Request& in) {
  Request r;
  r.method = in.method;
  r.path = in.path;
  for (const auto& [k, v] : in.params) r.query.emplace(k, v);
  return r;
}

}  // namespace

Server::Server(Studio& studio, ServerOptions options) : impl_(std::make_unique<Impl>(studio, std::move(options))) {
  auto& http = impl_->http;
  http.new_task_queue = [n = impl_->opt.threads] { return new httplib::ThreadPool(static_cast<size_t>(n)); };
  // Bodies are checked per route (Studio::body_limit) before they are read; this caps anything
  // that would still reach httplib's own reader.
  http.set_payload_max_length(impl_->opt.max_request_bytes);
  http.set_keep_alive_timeout(1);  // an idle browser connection gives its thread back soon
  // SO_REUSEADDR only: httplib's default also sets SO_REUSEPORT, which lets a second server bind
  // the same port and share its connections instead of failing.
  http.set_socket_options([](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  });

  // Before any body is read: its declared size against the route's limit. A client that sent
  // "Expect: 100-continue" (curl does for large bodies) is answered before it sends the body.
  http.set_expect_100_continue_handler([this](const httplib::Request& in, httplib::Response& out) {
    int status = 0;
    const std::string why = refuse_by_headers(in, impl_->studio.body_limit(in.method, in.path), status);
    if (why.empty()) return 100;
    out.status = status;
    out.set_content(error_body(why), "application/json");
    return status;
  });
  http.set_pre_routing_handler([this](const httplib::Request& in, httplib::Response& out) {
    int status = 0;
    const std::string why = refuse_by_headers(in, impl_->studio.body_limit(in.method, in.path), status);
    if (why.empty()) return httplib::Server::HandlerResponse::Unhandled;
    refuse_and_close(out, status, why);
    return httplib::Server::HandlerResponse::Handled;
  });

  auto get = [this](const httplib::Request& in, httplib::Response& out) {
    reply(impl_->studio.handle(studio_request(in)), out);
  };
  // Bodies are read here, in pieces, with the route's limit enforced while they arrive (also for
  // chunked bodies, which declare no length): JSON into memory, uploads into a file.
  auto with_body = [this](const httplib::Request& in, httplib::Response& out, const httplib::ContentReader& read) {
    Studio& studio = impl_->studio;
    const BodyLimit limit = studio.body_limit(in.method, in.path);
    Request r = studio_request(in);
    size_t received = 0;
    bool too_large = false;
    const std::string too_large_message = "request body of more than " + std::to_string(limit.bytes) +
                                          " bytes; at most " + std::to_string(limit.bytes) + " are accepted here";
    std::optional<Studio::UploadFile> file;
    int parts = 0;
    bool ok = true;
    try {
      if (limit.upload && r.query.count("name")) {
        // The name and route are checked before a byte is stored (the body itself comes next).
        Request named = r;
        named.body_file = "(streaming)";
        try {
          (void)check_request(named, studio.options());
          studio.check_upload_target(named.query.at("name"));
        } catch (const HttpError& e) {
          return refuse_and_close(out, e.status(), e.what());
        } catch (const PathRefused& e) {
          return refuse_and_close(out, 403, e.what());
        } catch (const Error& e) {
          return refuse_and_close(out, e.code() == ErrorCode::InvalidInput ? 400 : 500, e.what());
        }
      }
      if (limit.upload) {
        std::string ext;
        if (auto it = r.query.find("name"); it != r.query.end()) ext = std::filesystem::path(it->second).extension().string();
        file.emplace(studio.new_upload_file(ext));
        auto sink = [&](const char* data, size_t n) {
          received += n;
          if (received > limit.bytes) return too_large = true, false;
          file->write(data, n);
          return true;
        };
        if (in.is_multipart_form_data()) {
          // One file per upload: the first part's bytes; its file name when ?name= is absent.
          ok = read(
              [&](const httplib::MultipartFormData& part) {
                if (++parts > 1) return false;
                r.body_file_name = part.filename;
                return true;
              },
              sink);
          if (parts > 1) {
            refuse_and_close(out, 400, "a multipart upload must hold one file; this one holds more parts");
            return;
          }
        } else {
          ok = read(sink);
        }
        r.body_file = file->path();
      } else {
        if (in.is_multipart_form_data()) {
          refuse_and_close(out, 400, "this request takes a JSON body, not a multipart form");
          return;
        }
        ok = read([&](const char* data, size_t n) {
          received += n;
          if (received > limit.bytes) return too_large = true, false;
          r.body.append(data, n);
          return true;
        });
      }
    } catch (const Error& e) {
      refuse_and_close(out, 500, std::string(error_name(e.code())) + " error: " + e.what());
      return;
    }
    if (too_large) return refuse_and_close(out, 413, too_large_message);
    if (!ok) return refuse_and_close(out, 400, "the request body could not be read (cut off, or malformed framing)");
    reply(studio.handle(r), out);
  };
  http.Get(".*", get);
  http.Post(".*", with_body);
  http.Put(".*", with_body);
  http.Delete(".*", with_body);
  http.Patch(".*", with_body);
  http.set_error_handler([](const httplib::Request&, httplib::Response& out) {
    if (!out.body.empty() || out.content_length_ > 0) return;
    std::string msg = out.status == 413 ? "request too large" : "request refused (HTTP " + std::to_string(out.status) + ")";
    out.set_content(error_body(msg), "application/json");
  });
  // Never httplib's default, which puts the exception's text in a header.
  http.set_exception_handler([](const httplib::Request&, httplib::Response& out, std::exception_ptr ep) {
    std::string what = "unknown";
    try {
      if (ep) std::rethrow_exception(ep);
    } catch (const std::exception& e) {
      what = e.what();
    } catch (...) {
    }
    out.status = 500;
    out.set_content(error_body("internal error: " + what + " (please report this)"), "application/json");
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
