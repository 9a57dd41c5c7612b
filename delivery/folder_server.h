// A local HTTP server for one folder: a tileset and the page written beside
// it (viewer_page.h), which a browser cannot open from file:// URLs (its
// fetches of tileset.json and the tiles are refused there). Static files only,
// read-only, on the loopback interface, through cpp-httplib.
//
// Nothing outside the folder is served: a request path with a `..` part is
// refused, and so is a file the path reaches through a symbolic link that
// leads out of the folder.
#pragma once

#include <memory>
#include <optional>
#include <string>

namespace scan2lod {

struct FolderServerOptions {
  std::string host = "127.0.0.1";  // the loopback interface: this machine only
  int port = 8080;                 // 0: any free port (FolderServer::port() says which)
};

class FolderServer {
 public:
  // Binds the port. Throws InputError naming the folder when `dir` is not a
  // folder, or naming host:port when it cannot be bound (in use, or below
  // 1024 without the right) or is out of 0..65535.
  FolderServer(const std::string& dir, const FolderServerOptions& options = {});
  ~FolderServer();
  FolderServer(const FolderServer&) = delete;
  FolderServer& operator=(const FolderServer&) = delete;

  int port() const;
  std::string url() const;  // "http://127.0.0.1:PORT/"

  // Answers requests until stop() is called (from any thread); returns false
  // when the server stopped on its own (the socket failed).
  bool run();
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The file a request path (already %-decoded, starting with '/') names in the
// folder `root`: `index.html` for a folder. Empty when the path has a `..`
// part or a NUL, names nothing, or resolves (after symbolic links) outside
// `root`. `root` must be an absolute, canonical path.
std::optional<std::string> served_file(const std::string& root, const std::string& request_path);

// The Content-Type a file is served with, by its extension (any case):
// model/gltf-binary for .glb, application/json for .json, text/javascript for
// .js, text/html for .html, ...; application/octet-stream when unknown.
std::string content_type_of(const std::string& path);

}  // namespace scan2lod
