// scan2lod serve: a tileset's folder over HTTP on this machine
// (delivery/folder_server.h), so that a browser can open the page export
// wrote beside it. Runs until Ctrl-C (SIGINT) or SIGTERM.
#include <scan2lod/cli/commands.h>
#include <scan2lod/cli/terminal.h>
#include <scan2lod/core/error.h>
#include <scan2lod/delivery/folder_server.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <future>
#include <memory>
#include <thread>

#include <pthread.h>

namespace scan2lod::cli {
namespace {

// The signals that end serving. They are blocked in every thread (the
// server's pool inherits the mask) and taken by sigwait in the main thread,
// so that stopping runs as ordinary code rather than in a signal handler.
sigset_t stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGHUP);
  sigaddset(&set, SIGUSR1);  // sent to itself when the server ends on its own
  return set;
}

void serve(const std::string& dir, int port) {
  FolderServerOptions options;
  options.port = port;
  FolderServer server(dir, options);
  if (!std::filesystem::exists(std::filesystem::path(dir) / "tileset.json"))
    warn(dir + " holds no tileset.json; serving it anyway");
  const std::string page = std::filesystem::exists(std::filesystem::path(dir) / "index.html") ? "" : " (no index.html)";
  say("serving %s at %s%s; Ctrl-C stops\n", dir.c_str(), server.url().c_str(), page.c_str());
  std::fflush(stdout);  // a script reading the URL through a pipe needs it now

  const sigset_t signals = stop_signals();
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  const pthread_t main_thread = pthread_self();
  std::promise<bool> stopped_promise;
  std::future<bool> stopped = stopped_promise.get_future();
  std::thread listener([&] {
    const bool asked = server.run();
    stopped_promise.set_value(asked);
    pthread_kill(main_thread, SIGUSR1);
  });
  int signal = 0;
  sigwait(&signals, &signal);
  // stop() before the listener is listening does nothing; ask until it ends.
  do server.stop();
  while (stopped.wait_for(std::chrono::milliseconds(50)) != std::future_status::ready);
  listener.join();
  if (!stopped.get()) throw InputError(server.url(), "the server stopped: its socket failed");
  say("stopped\n");
}

}  // namespace

void add_serve_command(CLI::App& app) {
  struct Args {
    std::string dir;
    int port = 8080;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("serve", "A tileset's folder over HTTP on this machine, to open its page");
  cmd->add_option("dir", args->dir, "Folder written by export --format 3dtiles (tileset.json, index.html)")
      ->required();
  cmd->add_option("-p,--port", args->port, "Port on 127.0.0.1 (0: any free port, printed)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  cmd->callback([args] { serve(args->dir, args->port); });
}

}  // namespace scan2lod::cli
