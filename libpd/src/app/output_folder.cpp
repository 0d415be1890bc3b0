// Claiming a run's output folder: lock, writability, manifest.
#include "libpd/app/output_folder.hpp"

#include "libpd/core/atomic_file.hpp"
#include "libpd/core/file_input.hpp"
#include "libpd/core/text.hpp"
#include "libpd/io/checkpoint.hpp"

#include <cerrno>
#include <climits>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <sstream>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>
#include <vector>

namespace pd {

namespace {

constexpr const char* manifest_header = "# files written by a libpd run (pd run), one per line";

/// A manifest may name only plain files in the folder itself: nothing it lists can reach out.
bool is_plain_name(const std::string& name) {
  return !name.empty() && name.find('/') == std::string::npos && name != "." && name != "..";
}

std::set<std::string> read_manifest(const std::filesystem::path& file) {
  std::set<std::string> names;
  std::istringstream in(read_regular_file(file, std::size_t{64} << 20));
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#' && is_plain_name(line)) {
      names.insert(line);
    }
  }
  return names;
}

/// Run outputs in `dir` (by name), with or without a manifest.
std::vector<std::string> run_files_in(const std::filesystem::path& dir) {
  std::vector<std::string> found;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (is_run_output_name(name) || name == OutputFolder::manifest_name) {
      found.push_back(name);
    }
  }
  return found;
}

/// Every name a run may write in its folder: its outputs, the pieces of a split run, checkpoints.
bool may_be_written_by_a_run(const std::string& name) {
  return is_run_output_name(name) ||
         (name.starts_with("particles-") && (name.ends_with(".pvtu") || name.ends_with(".vtu"))) ||
         (name.starts_with("checkpoint") &&
          (name.ends_with(".pdcp") || name.ends_with(".pdcp.next") ||
           name.ends_with(".pdcp.complete")));
}

/// Symbolic links in `dir` under names the run writes: a run never writes through a link it did
/// not make, and a folder prepared with such links is an attack or a mistake either way.
std::vector<std::string> links_in(const std::filesystem::path& dir) {
  std::vector<std::string> found;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    std::error_code lec;
    if (may_be_written_by_a_run(name) && entry.is_symlink(lec)) {
      found.push_back(name);
    }
  }
  return found;
}

/// Room for the longest name a run writes in a folder with its temporary suffix (a split run's
/// "particles-<step>-r<rank>.pvtu.tmp-XXXXXXXXXXXX", "checkpoint-r<rank>of<ranks>.pdcp.tmp-…").
constexpr std::size_t longest_run_name = 64;

/// Refuses before the run a path the system could not open: a file written under it could never
/// be read back (nor given to --restart). PATH_MAX counts the terminating NUL.
void check_path_length(const std::filesystem::path& path, std::size_t room, const char* what) {
  const std::size_t length = path.native().size() + room;
  if (length >= PATH_MAX) {
    throw OutputFolderError(fmt::format(
        "{} is {} characters long; with the names the run writes in it the paths would reach {}, "
        "beyond the system's limit of {} (PATH_MAX): choose a shorter path",
        what, path.native().size(), length, PATH_MAX - 1));
  }
}

std::string list(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t k = 0; k < names.size() && k < 5; ++k) {
    s += (k ? ", " : "") + printable(names[k]);
  }
  return names.size() > 5 ? s + fmt::format(" and {} more", names.size() - 5) : s;
}

} // namespace

bool is_run_output_name(const std::string& name) {
  if (name == "summary.json" || name == "probes.csv" || name == "particles.pvd" ||
      name == "checkpoint.pdcp" || name == OutputFolder::manifest_name ||
      name == OutputFolder::lock_name) {
    return true;
  }
  return name.starts_with("particles-") && name.ends_with(".vtu");
}

OutputFolder::OutputFolder(std::filesystem::path dir, bool overwrite, bool continuing)
    : dir_(std::move(dir)) {
  check_path_length(dir_, 1 + longest_run_name, "the output folder (-o)");
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) {
    throw OutputFolderError(
        fmt::format("cannot create the output folder {}: {}", dir_.string(), ec.message()));
  }
  if (const std::vector<std::string> links = links_in(dir_); !links.empty()) {
    throw OutputFolderError(fmt::format(
        "the output folder {} holds symbolic links under names the run writes ({}): pd never "
        "writes through a link; remove them or choose another folder (-o)",
        dir_.string(), list(links)));
  }
  const int dir_fd = open_folder(dir_);
  if (dir_fd < 0) {
    throw OutputFolderError(
        fmt::format("cannot open the output folder {}: {}", dir_.string(), std::strerror(errno)));
  }
  // O_NOFOLLOW: a link planted under the lock's name after the check above is refused (ELOOP).
  lock_fd_ = ::openat(dir_fd, lock_name, O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
  const int open_errno = errno;
  ::close(dir_fd);
  if (lock_fd_ < 0) {
    throw OutputFolderError(fmt::format(
        "cannot write in the output folder {}: {}{}", dir_.string(), std::strerror(open_errno),
        open_errno == ELOOP ? fmt::format(" ({} is a symbolic link: remove it)", lock_name) : ""));
  }
  struct stat st {};
  if (::fstat(lock_fd_, &st) != 0 || !S_ISREG(st.st_mode) || st.st_nlink != 1) {
    ::close(lock_fd_);
    lock_fd_ = -1;
    // A hard link would let the pid written below truncate a file elsewhere.
    throw OutputFolderError(fmt::format(
        "the output folder's {} is not a plain file of its own (a hard link or a special file): "
        "remove it or choose another folder (-o)",
        (dir_ / lock_name).string()));
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    char pid[32] = {};
    const ssize_t n = ::pread(lock_fd_, pid, sizeof pid - 1, 0);
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw OutputFolderError(fmt::format(
        "the output folder {} is in use by another pd run{}: choose another folder (-o)",
        dir_.string(),
        n > 0 ? fmt::format(" (pid {})", std::string(pid, static_cast<std::size_t>(n))) : ""));
  }
  const std::string me = std::to_string(::getpid());
  if (::ftruncate(lock_fd_, 0) != 0 || ::pwrite(lock_fd_, me.data(), me.size(), 0) < 0) {
    // The pid is only a courtesy for the message above; the lock itself holds.
  }

  const std::filesystem::path manifest = dir_ / manifest_name;
  const bool has_manifest = std::filesystem::exists(manifest, ec);
  std::vector<std::string> present = run_files_in(dir_);
  std::erase(present, std::string(lock_name));
  if (continuing && has_manifest) {
    files_ = read_manifest(manifest);
    return;
  }
  if (present.empty()) {
    return;
  }
  if (!has_manifest) {
    throw OutputFolderError(fmt::format(
        "the output folder {} holds files of an earlier run without a manifest ({}); pd removes "
        "only files a manifest lists: delete them yourself or choose another folder (-o)",
        dir_.string(), list(present)));
  }
  if (!overwrite) {
    throw OutputFolderError(fmt::format(
        "the output folder {} holds another run's files ({}): give --overwrite to remove exactly "
        "the files of its {}, or choose another folder (-o)",
        dir_.string(), list(present), manifest_name));
  }
  for (const std::string& name : read_manifest(manifest)) {
    const auto p = dir_ / name;
    if (std::filesystem::is_regular_file(std::filesystem::symlink_status(p, ec))) {
      std::filesystem::remove(p, ec);
      if (ec) {
        throw OutputFolderError(
            fmt::format("cannot remove {} of the earlier run: {}", p.string(), ec.message()));
      }
    }
  }
  std::filesystem::remove(manifest, ec);
  present = run_files_in(dir_);
  std::erase(present, std::string(lock_name));
  if (!present.empty()) {
    throw OutputFolderError(fmt::format(
        "the output folder {} still holds run files its manifest did not list ({}): delete them "
        "yourself or choose another folder (-o)",
        dir_.string(), list(present)));
  }
}

OutputFolder::~OutputFolder() {
  if (lock_fd_ >= 0) {
    ::close(lock_fd_); // releases the flock
  }
}

void OutputFolder::add(const std::filesystem::path& path) {
  if (path.parent_path() != dir_) {
    return; // e.g. a checkpoint elsewhere: not this folder's to list
  }
  if (files_.insert(path.filename().string()).second) {
    write_manifest();
  }
}

void OutputFolder::write_manifest() const {
  std::string text = std::string(manifest_header) + "\n";
  for (const auto& f : files_) {
    text += f + "\n";
  }
  write_file_atomically(dir_ / manifest_name, text);
}

std::string OutputFolder::check_space(std::uint64_t bytes) const {
  struct statvfs fs {};
  if (::statvfs(dir_.c_str(), &fs) != 0) {
    return {};
  }
  const auto available = static_cast<std::uint64_t>(fs.f_bavail) * fs.f_frsize;
  const auto mib = [](std::uint64_t b) { return static_cast<double>(b) / (1024.0 * 1024.0); };
  if (bytes > available) {
    throw OutputFolderError(fmt::format(
        "the run will write about {:.0f} MiB into {}, which has {:.0f} MiB free: free space, "
        "write fewer VTU frames (output.vtu_every) or choose another folder (-o)",
        mib(bytes), dir_.string(), mib(available)));
  }
  if (2 * bytes > available) {
    return fmt::format("the run will write about {:.0f} MiB into {}, more than half of the {:.0f} "
                       "MiB free",
                       mib(bytes), dir_.string(), mib(available));
  }
  return {};
}

void check_checkpoint_target(const std::filesystem::path& checkpoint,
                             const std::filesystem::path& output_dir) {
  if (!output_dir.empty()) { // said of the folder first: the default checkpoint is inside it
    check_path_length(output_dir, 1 + longest_run_name, "the output folder (-o)");
  }
  // A split run adds "-r<rank>of<ranks>" to the name; every piece has a temporary first.
  check_path_length(checkpoint, longest_run_name, "the checkpoint path");
  std::error_code ec;
  const auto st = std::filesystem::status(checkpoint, ec);
  const std::string name = checkpoint.filename().string();
  if (!output_dir.empty() && name != "checkpoint.pdcp" && is_run_output_name(name) &&
      std::filesystem::weakly_canonical(checkpoint.parent_path(), ec) ==
          std::filesystem::weakly_canonical(output_dir, ec)) {
    throw OutputFolderError(fmt::format(
        "--checkpoint {} is a file the run itself writes: choose another name (default: "
        "{}/checkpoint.pdcp)",
        printable(checkpoint.string(), 400), printable(output_dir.string(), 400)));
  }
  if (std::filesystem::is_symlink(std::filesystem::symlink_status(checkpoint, ec))) {
    throw OutputFolderError(fmt::format(
        "--checkpoint {} is a symbolic link: pd never writes through a link; remove it or "
        "choose another path",
        printable(checkpoint.string(), 400)));
  }
  if (!std::filesystem::exists(st)) {
    return;
  }
  if (!std::filesystem::is_regular_file(st) || !is_checkpoint_file(checkpoint)) {
    throw OutputFolderError(fmt::format(
        "--checkpoint {} exists and is not a libpd checkpoint ({}): pd replaces only its own "
        "checkpoints; choose another path",
        printable(checkpoint.string(), 400),
        std::filesystem::is_regular_file(st) ? "wrong magic bytes" : "not a regular file"));
  }
}

} // namespace pd
