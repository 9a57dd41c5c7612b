#include <scan2lod/delivery/folder_server.h>

#include <scan2lod/core/error.h>
#include <scan2lod/io/file_extension.h>

#include <httplib.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <system_error>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;

// Why `host:port` cannot be bound: httplib only says that it failed, so the
// bind is tried once more here for the system's reason.
std::string bind_failure(const std::string& host, int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  int reason = 0;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(std::uint16_t(port));
  if (fd < 0) {
    reason = errno;
  } else if (::inet_pton(AF_INET, host.c_str(), &address.sin_addr) != 1) {
    ::close(fd);
    return "cannot listen on " + host + ": not an IPv4 address";
  } else {
    const int on = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);  // as httplib binds
    if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) reason = errno;
    ::close(fd);
  }
  const std::string where = host + ":" + std::to_string(port);
  if (reason == EADDRINUSE) return "cannot listen on " + where + ": port " + std::to_string(port) +
                                   " is in use (give another with --port, or --port 0 for any free one)";
  if (reason == EACCES) return "cannot listen on " + where + ": ports below 1024 need administrator rights";
  return "cannot listen on " + where + (reason ? std::string(": ") + std::strerror(reason) : std::string());
}

// Streams the file at `path` as the response, in pieces. A response given
// as a whole body would be compressed by httplib when the browser accepts
// brotli: at brotli's highest quality, which takes half a minute for
// CesiumJS's 6 MB script on these machines. A stream of known length is sent
// as it is. False when the file cannot be opened.
bool stream_file(const std::string& path, const std::string& type, httplib::Response& response) {
  auto in = std::make_shared<std::ifstream>(path, std::ios::binary);
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (!*in || ec) return false;
  response.set_content_provider(
      std::size_t(size), type, [in](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
        char buffer[1 << 16];
        in->seekg(std::streamoff(offset));
        in->read(buffer, std::streamsize(std::min(length, sizeof buffer)));
        const std::streamsize got = in->gcount();
        // A file cut short while being sent: ending the stream drops the connection.
        if (got <= 0) return false;
        sink.write(buffer, std::size_t(got));
        return true;
      });
  return true;
}

}  // namespace

std::optional<std::string> served_file(const std::string& root, const std::string& request_path) {
  if (request_path.empty() || request_path[0] != '/' || request_path.find('\0') != std::string::npos)
    return std::nullopt;
  fs::path path(root);
  for (const fs::path& part : fs::path(request_path).relative_path()) {
    if (part == "..") return std::nullopt;
    if (part.empty() || part == ".") continue;
    path /= part;
  }
  std::error_code ec;
  if (fs::is_directory(path, ec)) path /= "index.html";
  const fs::path real = fs::canonical(path, ec);
  if (ec || !fs::is_regular_file(real, ec)) return std::nullopt;
  // Inside `root` after every link is followed: root's parts are real's first parts.
  const fs::path base(root);
  const auto [mismatch, unused] = std::mismatch(base.begin(), base.end(), real.begin(), real.end());
  if (mismatch != base.end()) return std::nullopt;
  return real.string();
}

std::string content_type_of(const std::string& path) {
  static const std::pair<const char*, const char*> kTypes[] = {
      {".html", "text/html; charset=utf-8"},        {".htm", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},    {".mjs", "text/javascript; charset=utf-8"},
      {".json", "application/json"},                {".glb", "model/gltf-binary"},
      {".gltf", "model/gltf+json"},                 {".bin", "application/octet-stream"},
      {".wasm", "application/wasm"},                {".css", "text/css; charset=utf-8"},
      {".png", "image/png"},                        {".jpg", "image/jpeg"},
      {".jpeg", "image/jpeg"},                      {".ktx2", "image/ktx2"},
      {".svg", "image/svg+xml"},                    {".txt", "text/plain; charset=utf-8"},
  };
  const std::string ext = lower_extension(path);
  for (const auto& [e, type] : kTypes)
    if (ext == e) return type;
  return "application/octet-stream";
}

struct FolderServer::Impl {
  std::string root, host;
  int port = 0;
  httplib::Server server;
  std::atomic<bool> stopping{false};
};

FolderServer::FolderServer(const std::string& dir, const FolderServerOptions& options) : impl_(new Impl) {
  std::error_code ec;
  if (!fs::exists(dir, ec)) throw InputError(dir, "no such folder");
  if (!fs::is_directory(dir, ec)) throw InputError(dir, "is not a folder; serve takes a tileset's folder");
  impl_->root = fs::canonical(dir, ec).string();
  if (ec) throw InputError(dir, "cannot be opened: " + ec.message());
  if (options.port < 0 || options.port > 65535)
    throw InputError("", "--port must be 0 (any free port) to 65535, got " + std::to_string(options.port));
  impl_->host = options.host;

  Impl* impl = impl_.get();
  impl->server.Get(".*", [impl](const httplib::Request& request, httplib::Response& response) {
    const std::optional<std::string> file = served_file(impl->root, request.path);
    if (!file || !stream_file(*file, content_type_of(*file), response)) {
      response.status = 404;
      response.set_content("not found: " + request.path + "\n", "text/plain; charset=utf-8");
      return;
    }
    // Always asked again, so that a tileset exported anew shows on reload.
    response.set_header("Cache-Control", "no-cache");
  });

  // httplib's own options set SO_REUSEPORT, with which a second server binds
  // a port in use and the kernel shares the connections between the two.
  // SO_REUSEADDR alone lets a restarted server bind while the last one's
  // connections close, and refuses a port someone listens on.
  impl_->server.set_socket_options([](int socket) {
    const int on = 1;
    ::setsockopt(socket, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  });
  if (options.port == 0) {
    impl_->port = impl_->server.bind_to_any_port(options.host);
    if (impl_->port <= 0) throw InputError("", bind_failure(options.host, 0));
  } else {
    if (!impl_->server.bind_to_port(options.host.c_str(), options.port))
      throw InputError("", bind_failure(options.host, options.port));
    impl_->port = options.port;
  }
}

FolderServer::~FolderServer() { stop(); }

int FolderServer::port() const { return impl_->port; }

std::string FolderServer::url() const { return "http://" + impl_->host + ":" + std::to_string(impl_->port) + "/"; }

bool FolderServer::run() {
  impl_->server.listen_after_bind();
  return impl_->stopping.load();
}

void FolderServer::stop() {
  impl_->stopping = true;
  impl_->server.stop();
}

}  // namespace scan2lod
