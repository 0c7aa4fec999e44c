#include "catenary_sim/core/output_files.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>

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

// A temporary file beside `path` (same file system, so rename() is atomic).
std::FILE* open_temporary(const std::string& path, std::string* tmp) {
  if (path.empty()) throw OutputError("output file: empty path");
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
    throw OutputError("cannot write '" + path + "': it is a directory");
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

}  // namespace

AtomicFile::AtomicFile(const std::string& path) : path_(path) { file_ = open_temporary(path, &tmp_); }

AtomicFile::~AtomicFile() {
  if (file_) {
    std::fclose(file_);
    ::unlink(tmp_.c_str());
  }
}

void AtomicFile::write(const std::string& text) {
  if (!file_) throw OutputError("cannot write '" + path_ + "': already closed");
  if (std::fwrite(text.data(), 1, text.size(), file_) != text.size())
    throw OutputError("cannot write '" + path_ + "': " + reason());
}

void AtomicFile::flush() {
  if (!file_) throw OutputError("cannot write '" + path_ + "': already closed");
  // fflush and fsync report what a full disk or a quota refuses.
  if (std::fflush(file_) != 0 || ::fsync(::fileno(file_)) != 0 || std::ferror(file_))
    throw OutputError("cannot write '" + path_ + "': " + reason());
}

void AtomicFile::commit() {
  flush();
  std::FILE* f = file_;
  file_ = nullptr;
  if (std::fclose(f) != 0) {
    const std::string r = reason();
    ::unlink(tmp_.c_str());
    throw OutputError("cannot write '" + path_ + "': " + r);
  }
  if (::rename(tmp_.c_str(), path_.c_str()) != 0) {
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
  std::string tmp;
  std::FILE* f = open_temporary(path, &tmp);
  std::fclose(f);
  ::unlink(tmp.c_str());
}

void make_directories(const std::string& dir) {
  if (dir.empty()) throw OutputError("output directory: empty path");
  std::string cur;
  std::stringstream ss(dir);
  if (dir[0] == '/') cur = "/";
  for (std::string part; std::getline(ss, part, '/');) {
    if (part.empty()) continue;
    cur += part + "/";
    if (::mkdir(cur.c_str(), 0755) != 0 && errno != EEXIST)
      throw OutputError("cannot create directory '" + cur + "': " + reason());
  }
  struct stat st {};
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw OutputError("cannot use '" + dir + "' as an output directory: not a directory");
}

DirectoryLock::DirectoryLock(const std::string& dir) {
  const std::string name = dir + "/.catenary_sim.lock";
  fd_ = ::open(name.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
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

}  // namespace catenary_sim
