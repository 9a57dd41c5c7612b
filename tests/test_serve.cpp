// scan2lod serve (delivery/folder_server.h): a folder's files over real HTTP
// on the loopback interface, each with its type, and nothing outside the
// folder, however the path is spelled. Requests are written by hand on a
// socket, so that paths no client library would send reach the server as
// they are.
#include <scan2lod/core/error.h>
#include <scan2lod/delivery/folder_server.h>
#include "test_support.h"

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

namespace scan2lod {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::scratch_folder;

struct Reply {
  int status = 0;
  std::string content_type, body;
};

// One HTTP/1.1 GET of `target`, exactly as given, on 127.0.0.1:port.
Reply http_get(int port, const std::string& target) {
  Reply reply;
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(std::uint16_t(port));
  ::inet_pton(AF_INET, "127.0.0.1", &address.sin_addr);
  // A server that never answers fails the test instead of hanging it.
  const timeval timeout{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    ::close(fd);
    return reply;
  }
  const std::string request = "GET " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
  if (::send(fd, request.data(), request.size(), 0) != ssize_t(request.size())) {
    ::close(fd);
    return reply;
  }
  std::string text;
  char buffer[4096];
  for (ssize_t n; (n = ::recv(fd, buffer, sizeof buffer, 0)) > 0;) text.append(buffer, std::size_t(n));
  ::close(fd);
  const std::size_t head_end = text.find("\r\n\r\n");
  if (text.rfind("HTTP/1.1 ", 0) != 0 || head_end == std::string::npos) return reply;
  reply.status = std::stoi(text.substr(9, 3));
  const std::string head = text.substr(0, head_end);
  const std::size_t type = head.find("\r\nContent-Type: ");
  if (type != std::string::npos) {
    const std::size_t from = type + 16;
    reply.content_type = head.substr(from, head.find("\r\n", from) - from);
  }
  reply.body = text.substr(head_end + 4);
  return reply;
}

void write_text(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// A server on a free port, answering on its own thread while the test runs.
struct RunningServer {
  FolderServer server;
  std::thread thread;
  explicit RunningServer(const fs::path& dir) : server(dir.string(), {"127.0.0.1", 0}) {
    thread = std::thread([this] { server.run(); });
  }
  ~RunningServer() {
    // stop() before the thread listens does nothing: ask until it has ended.
    while (true) {
      server.stop();
      if (http_get(server.port(), "/").status == 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    thread.join();
  }
};

// A tileset-like folder, and a secret beside it that must never be served.
fs::path site() {
  const fs::path root = scratch_folder("serve");
  const fs::path dir = root / "site";
  write_text(dir / "index.html", "<!doctype html><title>page</title>");
  write_text(dir / "viewer.js", "console.log(1);");
  write_text(dir / "tileset.json", R"({"asset":{"version":"1.1"}})");
  write_text(dir / "tiles" / "0.glb", std::string("glTF\x02\0\0\0", 8));
  write_text(root / "secret.txt", "the secret");
  std::error_code ec;
  fs::create_symlink(root / "secret.txt", dir / "out.txt", ec);
  fs::create_symlink(dir / "tileset.json", dir / "in.json", ec);
  return dir;
}

Reply wait_for_first(int port, const std::string& target) {
  Reply r;
  for (int i = 0; i < 100 && r.status == 0; ++i) {
    r = http_get(port, target);
    if (r.status == 0) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return r;
}

}  // namespace

TEST(Serve, AnswersEachFileWithItsType) {
  const fs::path dir = site();
  RunningServer s(dir);
  EXPECT_EQ(s.server.url(), "http://127.0.0.1:" + std::to_string(s.server.port()) + "/");
  const Reply root = wait_for_first(s.server.port(), "/");
  EXPECT_EQ(root.status, 200);
  EXPECT_EQ(root.content_type, "text/html; charset=utf-8");
  EXPECT_EQ(root.body, "<!doctype html><title>page</title>");
  const struct {
    const char* target;
    const char* type;
  } files[] = {{"/index.html?camera=1", "text/html; charset=utf-8"},
               {"/viewer.js", "text/javascript; charset=utf-8"},
               {"/tileset.json", "application/json"},
               {"/tiles/0.glb", "model/gltf-binary"},
               {"/tiles/%30.glb", "model/gltf-binary"},
               {"/in.json", "application/json"}};
  for (const auto& f : files) {
    const Reply r = http_get(s.server.port(), f.target);
    EXPECT_EQ(r.status, 200) << f.target;
    EXPECT_EQ(r.content_type, f.type) << f.target;
  }
  EXPECT_EQ(http_get(s.server.port(), "/tiles/0.glb").body, std::string("glTF\x02\0\0\0", 8));
  EXPECT_EQ(http_get(s.server.port(), "/missing.glb").status, 404);
}

TEST(Serve, ServesNothingOutsideTheFolder) {
  const fs::path dir = site();
  RunningServer s(dir);
  wait_for_first(s.server.port(), "/");
  for (const char* target : {"/../secret.txt", "/%2e%2e/secret.txt", "/tiles/../../secret.txt",
                             "/tiles/%2E%2E/%2E%2E/secret.txt", "/..%2fsecret.txt", "/out.txt", "//secret.txt"}) {
    const Reply r = http_get(s.server.port(), target);
    EXPECT_NE(r.status, 200) << target;
    EXPECT_EQ(r.body.find("the secret"), std::string::npos) << target;
  }
}

TEST(Serve, ServedFileResolvesInsideTheRootOnly) {
  const fs::path dir = fs::canonical(site());
  EXPECT_EQ(served_file(dir.string(), "/"), (dir / "index.html").string());
  EXPECT_EQ(served_file(dir.string(), "/./tiles//0.glb"), (dir / "tiles" / "0.glb").string());
  EXPECT_FALSE(served_file(dir.string(), "/tiles/../tileset.json"));  // no `..` at all, even inside
  EXPECT_FALSE(served_file(dir.string(), "/out.txt"));
  EXPECT_FALSE(served_file(dir.string(), "tileset.json"));
  EXPECT_FALSE(served_file(dir.string(), std::string("/tileset.json\0.glb", 18)));
  EXPECT_EQ(content_type_of("a/B.GLB"), "model/gltf-binary");
  EXPECT_EQ(content_type_of("x.subtree"), "application/octet-stream");
}

TEST(Serve, APortInUseIsNamed) {
  const fs::path dir = site();
  RunningServer first(dir);
  const int port = first.server.port();
  try {
    FolderServer second(dir.string(), {"127.0.0.1", port});
    FAIL() << "a second server bound port " << port;
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("port " + std::to_string(port) + " is in use"), std::string::npos) << what;
  }
}

TEST(Serve, CommandLineRefusesAMissingFolderAndABadPort) {
  const testing::CliRun missing = run_cli("serve /no/such/tileset --port 0");
  EXPECT_EQ(testing::exit_code(missing), 1) << missing.output;
  EXPECT_NE(missing.output.find("/no/such/tileset: no such folder"), std::string::npos) << missing.output;
  const testing::CliRun file = run_cli("serve " + (site() / "index.html").string() + " --port 0");
  EXPECT_EQ(testing::exit_code(file), 1) << file.output;
  EXPECT_NE(file.output.find("is not a folder"), std::string::npos) << file.output;
  const testing::CliRun port = run_cli("serve " + site().string() + " --port 70000");
  EXPECT_EQ(testing::exit_code(port), 2) << port.output;
}

}  // namespace scan2lod
