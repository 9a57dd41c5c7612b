#include <scan2lod/io/atomic_file.h>

#include <scan2lod/core/error.h>

#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <system_error>

namespace scan2lod {

namespace fs = std::filesystem;

namespace {

// ---------------------------------------------------------------------------
// Temporary names removed on SIGINT, SIGTERM and SIGHUP.
//
// The handler may run on any thread at any moment, so the table is a fixed
// array the handler only reads, and all it calls is unlink, sigaction and
// raise. A slot is claimed (free -> filling), filled, then published
// (registered); its generation changes before each refill, so a handler that
// copied a path while the slot was reused sees the change and reads it again.

constexpr int kSlots = 64;  // writes in flight at once; more just go unprotected
enum SlotState : int { kFree = 0, kFilling = 1, kRegistered = 2 };

struct TempSlot {
  std::atomic<int> state{kFree};
  std::atomic<unsigned> generation{0};
  char path[PATH_MAX];
};
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<unsigned>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

TempSlot g_slots[kSlots];
constexpr int kCaught[] = {SIGINT, SIGTERM, SIGHUP};
constexpr int kCaughtCount = sizeof kCaught / sizeof kCaught[0];
struct sigaction g_previous[kCaughtCount];

void remove_one(TempSlot& slot) {
  for (int attempt = 0; attempt < 3; ++attempt) {
    if (slot.state.load() != kRegistered) return;
    const unsigned generation = slot.generation.load();
    char path[PATH_MAX];
    for (int i = 0; i < PATH_MAX; ++i)
      if ((path[i] = slot.path[i]) == '\0') break;
    path[PATH_MAX - 1] = '\0';
    if (slot.state.load() == kRegistered && slot.generation.load() == generation) {
      ::unlink(path);
      return;
    }
  }
}

extern "C" void remove_temporaries_and_reraise(int sig) {
  const int saved_errno = errno;
  for (TempSlot& slot : g_slots) remove_one(slot);
  // The previous disposition decides what the signal does (usually: end the
  // process with it, so the exit status still says which signal it was).
  for (int i = 0; i < kCaughtCount; ++i)
    if (kCaught[i] == sig) ::sigaction(sig, &g_previous[i], nullptr);
  ::raise(sig);  // blocked until this handler returns
  errno = saved_errno;
}

void install_signal_handlers() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (int i = 0; i < kCaughtCount; ++i) {
      struct sigaction previous {};
      if (::sigaction(kCaught[i], nullptr, &previous) != 0) continue;
      // An ignored signal (nohup, a shell's background job) stays ignored.
      if (!(previous.sa_flags & SA_SIGINFO) && previous.sa_handler == SIG_IGN) continue;
      g_previous[i] = previous;
      struct sigaction ours {};
      ours.sa_handler = remove_temporaries_and_reraise;
      sigfillset(&ours.sa_mask);
      ours.sa_flags = SA_RESTART;
      ::sigaction(kCaught[i], &ours, nullptr);
    }
  });
}

// Keeps `path` in the table for its lifetime: a signal meanwhile unlinks it.
class RemovedOnSignal {
 public:
  explicit RemovedOnSignal(const fs::path& path) {
    install_signal_handlers();
    const std::string& text = path.native();
    if (text.size() >= PATH_MAX) return;
    for (int i = 0; i < kSlots; ++i) {
      int expected = kFree;
      if (!g_slots[i].state.compare_exchange_strong(expected, kFilling)) continue;
      g_slots[i].generation.fetch_add(1);
      std::memcpy(g_slots[i].path, text.c_str(), text.size() + 1);
      g_slots[i].state.store(kRegistered);
      slot_ = i;
      return;
    }
  }
  ~RemovedOnSignal() {
    if (slot_ >= 0) g_slots[slot_].state.store(kFree);
  }
  RemovedOnSignal(const RemovedOnSignal&) = delete;
  RemovedOnSignal& operator=(const RemovedOnSignal&) = delete;

 private:
  int slot_ = -1;
};

// ---------------------------------------------------------------------------
// The output, examined before anything is written.

struct OutputTarget {
  fs::path file;    // the path with symbolic links followed to the end
  fs::path folder;  // the folder file goes into
  bool exists = false;
  struct stat status {};  // of file, when it exists
};

std::string errno_text(int err) { return std::strerror(err); }

// " (X, where the link leads)" when the user's path is a link, else "".
std::string via_link(const std::string& path, const OutputTarget& t) {
  return t.file.native() == path ? std::string() : " (" + t.file.string() + ", where the link leads)";
}

fs::path follow_links(const std::string& path) {
  fs::path p(path);
  for (int hops = 0;; ++hops) {
    struct stat st;
    if (::lstat(p.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return p;
    if (hops == 40) throw InputError(path, "cannot write: too many levels of symbolic links");
    std::error_code ec;
    const fs::path next = fs::read_symlink(p, ec);
    if (ec) throw InputError(path, "cannot read the symbolic link: " + ec.message());
    p = next.is_absolute() ? next : p.parent_path() / next;
  }
}

OutputTarget examine_output(const std::string& path) {
  if (path.empty()) throw InputError(path, "expected a file name to write");
  OutputTarget t;
  t.file = follow_links(path);
  t.folder = t.file.parent_path().empty() ? fs::path(".") : t.file.parent_path();
  t.exists = ::stat(t.file.c_str(), &t.status) == 0;
  if (t.exists && S_ISDIR(t.status.st_mode))
    throw InputError(path, "is a folder; expected a file name to write");
  // Renaming over a device or a pipe would replace it, not write to it.
  if (t.exists && !S_ISREG(t.status.st_mode))
    throw InputError(path, "is not a regular file" + via_link(path, t) +
                               " but a device, pipe or socket; expected a file name to write");
  struct stat folder {};
  if (::stat(t.folder.c_str(), &folder) != 0 || !S_ISDIR(folder.st_mode))
    throw InputError(path, "cannot write: folder " + t.folder.string() + " does not exist");
  if (::faccessat(AT_FDCWD, t.folder.c_str(), W_OK | X_OK, AT_EACCESS) != 0)
    throw InputError(path, "cannot write into folder " + t.folder.string() + ": " + errno_text(errno));
  if (t.exists && ::faccessat(AT_FDCWD, t.file.c_str(), W_OK, AT_EACCESS) != 0)
    throw InputError(path, "cannot write" + via_link(path, t) + ": " + errno_text(errno));
  // rename(2) over another user's file in a sticky folder fails with EPERM.
  const uid_t me = ::geteuid();
  if (t.exists && (folder.st_mode & S_ISVTX) && me != 0 && t.status.st_uid != me && folder.st_uid != me)
    throw InputError(path, "cannot replace" + via_link(path, t) + ": it belongs to another user and folder " +
                               t.folder.string() + " is sticky (only a file's owner may replace it)");
  return t;
}

// ---------------------------------------------------------------------------
// Putting the finished file in place.

class FdCloser {
 public:
  explicit FdCloser(int fd) : fd_(fd) {}
  ~FdCloser() { ::close(fd_); }
  FdCloser(const FdCloser&) = delete;
  FdCloser& operator=(const FdCloser&) = delete;

 private:
  int fd_;
};

// A name beside the target, hidden, unique in this process; the extension
// stays last for writers that look at it.
fs::path hidden_name(const OutputTarget& t) {
  static std::atomic<unsigned> counter{0};
  const unsigned n = counter.fetch_add(1);
  std::string name = ".tmp-" + std::to_string(::getpid()) + "-";
  if (n > 0) name += std::to_string(n) + "-";
  return t.folder / (name + t.file.filename().string());
}

[[noreturn]] void cannot_place(const std::string& path, const OutputTarget& t, int err) {
  std::string reason = errno_text(err);
  std::error_code ec;
  if (fs::is_directory(t.file, ec)) reason = "a folder of that name is in the way";
  throw InputError(path, "cannot move the finished file into place" + via_link(path, t) + ": " + reason);
}

void check_not_empty(const std::string& path, const struct stat& written) {
  if (written.st_size == 0) throw InputError(path, "writer produced no output");
}

// The replaced file's owner, group (where this user may set them; as root,
// or a group the user is in) and mode. The owner goes first: chown clears
// set-user-ID bits.
void keep_attributes(int fd, const OutputTarget& t) {
  if (!t.exists) return;
  const uid_t uid = t.status.st_uid;
  const gid_t gid = t.status.st_gid;
  if ((uid != ::geteuid() || gid != ::getegid()) && ::fchown(fd, uid, gid) != 0)
    (void)::fchown(fd, uid_t(-1), gid);
  (void)::fchmod(fd, t.status.st_mode & 07777);
}

bool anonymous_files_allowed() {
  static const bool allowed = [] {
    const char* choice = std::getenv("SCAN2LOD_TEMP_FILES");
    if (choice && std::strcmp(choice, "named") == 0) return false;
    return ::access("/proc/self/fd", X_OK) == 0;  // writers reach the file by a /proc path
  }();
  return allowed;
}

// An anonymous file in the target's folder, or -1 where the file system has
// none (EOPNOTSUPP), or the kernel predates them (EISDIR, EINVAL).
int open_anonymous(const std::string& path, const OutputTarget& t, mode_t* new_file_mode) {
  if (!anonymous_files_allowed()) return -1;
  const int fd = ::open(t.folder.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
  if (fd < 0) {
    const int err = errno;
    if (err == EOPNOTSUPP || err == EISDIR || err == EINVAL) return -1;
    throw InputError(path, "cannot write into folder " + t.folder.string() + ": " + errno_text(err));
  }
  // What umask and default ACLs make of 0666: the mode a new file gets.
  struct stat st;
  ::fstat(fd, &st);
  *new_file_mode = st.st_mode & 07777;
  // Meanwhile the writer, reopening the file by its /proc name, needs it
  // readable and writable whatever the umask says.
  ::fchmod(fd, 0600);
  return fd;
}

void link_into_place(const std::string& path, const OutputTarget& t, const std::string& proc_path) {
  // A new file: linkat cannot replace, but then it need not.
  if (!t.exists) {
    if (::linkat(AT_FDCWD, proc_path.c_str(), AT_FDCWD, t.file.c_str(), AT_SYMLINK_FOLLOW) == 0) return;
    if (errno != EEXIST) cannot_place(path, t, errno);
  }
  // Replacing: link under a hidden name, then rename over the target. Only
  // these two system calls lie between; a signal then unlinks the hidden name.
  const fs::path hidden = hidden_name(t);
  RemovedOnSignal guard(hidden);
  int linked = ::linkat(AT_FDCWD, proc_path.c_str(), AT_FDCWD, hidden.c_str(), AT_SYMLINK_FOLLOW);
  if (linked != 0 && errno == EEXIST) {  // left by a killed process with our id
    ::unlink(hidden.c_str());
    linked = ::linkat(AT_FDCWD, proc_path.c_str(), AT_FDCWD, hidden.c_str(), AT_SYMLINK_FOLLOW);
  }
  if (linked != 0) cannot_place(path, t, errno);
  if (::rename(hidden.c_str(), t.file.c_str()) != 0) {
    const int err = errno;
    ::unlink(hidden.c_str());
    cannot_place(path, t, err);
  }
}

void write_anonymous(const std::string& path, const OutputTarget& t, int fd, mode_t new_file_mode,
                     const std::function<void(const std::string&)>& write) {
  FdCloser closer(fd);  // closing an unlinked anonymous file frees it
  const std::string proc_path = "/proc/self/fd/" + std::to_string(fd);
  write(proc_path);
  struct stat written;
  if (::fstat(fd, &written) != 0) throw InputError(path, "cannot inspect the written file: " + errno_text(errno));
  check_not_empty(path, written);
  if (t.exists) keep_attributes(fd, t);
  else ::fchmod(fd, new_file_mode);
  link_into_place(path, t, proc_path);
}

void write_named(const std::string& path, const OutputTarget& t,
                 const std::function<void(const std::string&)>& write) {
  const fs::path tmp = hidden_name(t);
  RemovedOnSignal guard(tmp);
  try {
    write(tmp.string());
    const int fd = ::open(tmp.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0) throw InputError(path, "writer produced no output");
    FdCloser closer(fd);
    struct stat written;
    if (::fstat(fd, &written) != 0) throw InputError(path, "cannot inspect the written file: " + errno_text(errno));
    check_not_empty(path, written);
    keep_attributes(fd, t);
  } catch (...) {
    ::unlink(tmp.c_str());
    throw;
  }
  // rename(2) itself, so that the message is its errno, not a wrapper's.
  if (std::rename(tmp.c_str(), t.file.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    cannot_place(path, t, err);
  }
}

}  // namespace

void check_output_path(const std::string& path) { examine_output(path); }

void check_output_folder(const std::string& folder) {
  if (folder.empty()) throw InputError(folder, "expected a folder name to write into");
  fs::path p(folder);
  std::error_code ec;
  if (fs::exists(p, ec) && !fs::is_directory(p, ec))
    throw InputError(folder, "is a file; expected a folder to write into");
  // The folder itself, or the first one above it that exists (to create it in).
  while (!fs::exists(p, ec)) {
    p = p.has_parent_path() && p.parent_path() != p ? p.parent_path() : fs::path(".");
    if (p == ".") break;
  }
  if (!fs::is_directory(p, ec))
    throw InputError(folder, "cannot create the folder: " + p.string() + " is not a folder");
  if (::faccessat(AT_FDCWD, p.c_str(), W_OK | X_OK, AT_EACCESS) != 0)
    throw InputError(folder, "cannot write into folder " + p.string() + ": " + errno_text(errno));
}

void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write) {
  const OutputTarget t = examine_output(path);
  mode_t new_file_mode = 0644;
  const int fd = open_anonymous(path, t, &new_file_mode);
  if (fd >= 0) write_anonymous(path, t, fd, new_file_mode, write);
  else write_named(path, t, write);
}

}  // namespace scan2lod
