#include "catenary_sim/core/output/output_files.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <sstream>
#include <vector>

namespace catenary_sim {
namespace {

std::string reason() { return std::strerror(errno); }

std::string directory_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string base_name(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// What a file of this mode is, for a refusal.
const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// A temporary file beside `path` (same file system, so rename() is atomic).
std::FILE* open_temporary(const std::string& path, std::string* tmp) {
  if (path.empty()) throw OutputError("output file: empty path");
  std::string name = directory_of(path) + "/." + base_name(path) + ".tmp.XXXXXX";
  const int fd = ::mkstemp(&name[0]);
  if (fd < 0) throw OutputError("cannot write '" + path + "': " + reason());
  ::fchmod(fd, 0644);
  std::FILE* f = ::fdopen(fd, "w");
  if (!f) {
    const std::string why = reason();
    ::close(fd);
    ::unlink(name.c_str());
    throw OutputError("cannot write '" + path + "': " + why);
  }
  *tmp = name;
  return f;
}

// SIGPIPE blocked in this thread while a stream is written: a reader that went away makes the
// write fail with EPIPE (an OutputError) instead of killing the program. A SIGPIPE raised meanwhile
// is taken off the thread's pending set so that unblocking does not deliver it.
class QuietPipe {
 public:
  explicit QuietPipe(bool on) : on_(on) {
    if (!on_) return;
    sigemptyset(&pipe_);
    sigaddset(&pipe_, SIGPIPE);
    sigset_t pending;
    sigpending(&pending);
    was_pending_ = sigismember(&pending, SIGPIPE) == 1;
    pthread_sigmask(SIG_BLOCK, &pipe_, &old_);
  }
  ~QuietPipe() {
    if (!on_) return;
    sigset_t pending;
    sigpending(&pending);
    if (!was_pending_ && sigismember(&pending, SIGPIPE) == 1) {
      const timespec zero{0, 0};
      sigtimedwait(&pipe_, nullptr, &zero);
    }
    pthread_sigmask(SIG_SETMASK, &old_, nullptr);
  }
  QuietPipe(const QuietPipe&) = delete;
  QuietPipe& operator=(const QuietPipe&) = delete;

 private:
  bool on_ = false, was_pending_ = false;
  sigset_t pipe_{}, old_{};
};

// A FIFO or character device opened for writing in place. O_NONBLOCK only for the open: a FIFO
// without a reader is refused at once (ENXIO) instead of waiting for one without end.
std::FILE* open_stream(const std::string& shown, const std::string& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) {
    if (errno == ENXIO)
      throw OutputError("cannot write '" + shown + "': it is a FIFO with no reader (start the reader first)");
    throw OutputError("cannot write '" + shown + "': " + reason());
  }
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  std::FILE* f = ::fdopen(fd, "w");
  if (!f) {
    const std::string why = reason();
    ::close(fd);
    throw OutputError("cannot write '" + shown + "': " + why);
  }
  return f;
}

}  // namespace

OutputTarget output_target(const std::string& path) {
  if (path.empty()) throw OutputError("output file: empty path");
  std::string p = path;
  for (int links = 0;; ++links) {
    struct stat st {};
    // Not there (or not visible): a new file, whose creation names any reason it cannot be.
    if (::lstat(p.c_str(), &st) != 0) return OutputTarget{p, false};
    if (S_ISREG(st.st_mode)) return OutputTarget{p, false};
    if (S_ISFIFO(st.st_mode) || S_ISCHR(st.st_mode)) return OutputTarget{p, true};
    if (!S_ISLNK(st.st_mode)) {
      const std::string what = p == path ? std::string("it is ") + kind_of(st.st_mode)
                                         : "it links to '" + p + "', " + kind_of(st.st_mode);
      throw OutputError("cannot write '" + path + "': " + what);
    }
    // The link is kept and what it names is written (as `ln -s` users expect of `>`).
    if (links >= 40) throw OutputError("cannot write '" + path + "': too many levels of symbolic links");
    std::vector<char> buf(PATH_MAX + 1);
    const ssize_t n = ::readlink(p.c_str(), buf.data(), buf.size() - 1);
    if (n < 0) throw OutputError("cannot write '" + path + "': " + reason());
    const std::string to(buf.data(), static_cast<std::size_t>(n));
    p = !to.empty() && to[0] == '/' ? to : directory_of(p) + "/" + to;
  }
}

AtomicFile::AtomicFile(const std::string& path) : path_(path) {
  const OutputTarget t = output_target(path);
  target_ = t.path;
  stream_ = t.stream;
  file_ = stream_ ? open_stream(path, target_) : open_temporary(target_, &tmp_);
}

AtomicFile::~AtomicFile() {
  if (file_) {
    const QuietPipe quiet(stream_);
    std::fclose(file_);
    if (!stream_) ::unlink(tmp_.c_str());
  }
}

void AtomicFile::write(const std::string& text) {
  if (!file_) throw OutputError("cannot write '" + path_ + "': already closed");
  const QuietPipe quiet(stream_);
  synced_ = false;
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size())
    throw OutputError("cannot write '" + path_ + "': " + reason());
}

void AtomicFile::start_writeback() {
  if (!file_) throw OutputError("cannot write '" + path_ + "': already closed");
  const QuietPipe quiet(stream_);
  if (std::fflush(file_) != 0 || std::ferror(file_)) throw OutputError("cannot write '" + path_ + "': " + reason());
  // Advice only: a failure here is found again, and reported, by flush()'s fsync.
  if (!stream_) ::sync_file_range(::fileno(file_), 0, 0, SYNC_FILE_RANGE_WRITE);
}

void AtomicFile::flush() {
  if (!file_) throw OutputError("cannot write '" + path_ + "': already closed");
  const QuietPipe quiet(stream_);
  // fflush and fsync report what a full disk or a quota refuses (a pipe or device has no fsync).
  if (std::fflush(file_) != 0 || (!stream_ && ::fsync(::fileno(file_)) != 0) || std::ferror(file_))
    throw OutputError("cannot write '" + path_ + "': " + reason());
  synced_ = true;
}

void AtomicFile::commit() {
  // A file flushed since its last write is on the disk: a second fsync would only wait again.
  if (!synced_) flush();
  std::FILE* f = file_;
  file_ = nullptr;
  const QuietPipe quiet(stream_);
  if (std::fclose(f) != 0) {
    const std::string r = reason();
    if (!stream_) ::unlink(tmp_.c_str());
    throw OutputError("cannot write '" + path_ + "': " + r);
  }
  if (stream_) return;
  if (::rename(tmp_.c_str(), target_.c_str()) != 0) {
    const std::string r = reason();
    ::unlink(tmp_.c_str());
    throw OutputError("cannot write '" + path_ + "': " + r);
  }
}

void write_file_atomically(const std::string& path, const std::string& content) {
  AtomicFile f(path);
  f.write(content);
  f.commit();
}

void check_writable(const std::string& path) {
  const OutputTarget t = output_target(path);
  if (t.stream) {
    // Not opened now: a FIFO's reader may start later, and a device is written only at the end.
    if (::access(t.path.c_str(), W_OK) != 0) throw OutputError("cannot write '" + path + "': " + reason());
    return;
  }
  std::string tmp;
  std::FILE* f = open_temporary(t.path, &tmp);
  std::fclose(f);
  ::unlink(tmp.c_str());
}

std::vector<std::string> make_directories(const std::string& dir) {
  if (dir.empty()) throw OutputError("output directory: empty path");
  std::vector<std::string> made;
  std::string cur;
  std::stringstream ss(dir);
  if (dir[0] == '/') cur = "/";
  for (std::string part; std::getline(ss, part, '/');) {
    if (part.empty()) continue;
    cur += part + "/";
    if (::mkdir(cur.c_str(), 0755) == 0) made.push_back(cur);
    else if (errno != EEXIST) throw OutputError("cannot create directory '" + cur + "': " + reason());
  }
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw OutputError("cannot use '" + dir + "' as an output directory: not a directory");
  return made;
}

void remove_made_directories(const std::vector<std::string>& made) {
  for (auto it = made.rbegin(); it != made.rend(); ++it) ::rmdir(it->c_str());  // (fails, harmlessly, if not empty)
}

DirectoryLock::DirectoryLock(const std::string& dir) : path_(dir + "/.catenary_sim.lock") {
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  made_ = fd_ >= 0;
  if (fd_ < 0 && errno == EEXIST) fd_ = ::open(path_.c_str(), O_RDWR | O_CLOEXEC);
  if (fd_ < 0) throw OutputError("cannot lock output directory '" + dir + "': " + reason());
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const bool busy = errno == EWOULDBLOCK;
    const std::string why = reason();
    ::close(fd_);
    fd_ = -1;
    throw OutputError(busy ? "output directory '" + dir + "' is being written by another run; choose another --out or wait"
                           : "cannot lock output directory '" + dir + "': " + why);
  }
}

DirectoryLock::~DirectoryLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

void DirectoryLock::remove_if_made() {
  if (made_ && fd_ >= 0) ::unlink(path_.c_str());
  made_ = false;
}

}  // namespace catenary_sim
