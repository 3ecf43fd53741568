// SPDX-License-Identifier: MIT
#include "ballbar/fileio/output.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <random>

namespace ballbar::fileio {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void fail(const std::string& what, int err) {
    throw FileError(FileError::Kind::failed, "cannot write " + what + ": " + std::strerror(err));
}

/// /dev/… and /proc/… (as written, or once made absolute): the operator's streams and devices.
bool system_path(const std::string& path) {
    std::error_code ec;
    const std::string abs = fs::absolute(path, ec).lexically_normal().string();
    return abs.rfind("/dev/", 0) == 0 || abs.rfind("/proc/", 0) == 0;
}

std::string random_suffix() {
    static const char digits[] = "0123456789abcdefghijklmnopqrstuvwxyz";
    std::random_device rd;
    std::string s;
    for (int i = 0; i < 8; ++i) s += digits[rd() % 36];
    return s;
}

}  // namespace

void refuse_if_input(const std::string& path, std::string_view option, const std::vector<Protected>& inputs) {
    struct stat out {};
    if (::stat(path.c_str(), &out) != 0) return;  // not there yet: it is none of the inputs
    for (const auto& in : inputs) {
        struct stat st {};
        if (in.path.empty() || ::stat(in.path.c_str(), &st) != 0) continue;
        if (st.st_dev == out.st_dev && st.st_ino == out.st_ino) {
            throw FileError(FileError::Kind::refused, std::string(option) + " " + path + " is the " + in.role +
                                                          (in.path == path ? "" : " (" + in.path + ")") +
                                                          ": it would be overwritten (choose another file)");
        }
    }
}

void check_output(const std::string& path, std::string_view option, const std::vector<Protected>& inputs) {
    if (path == "-") return;
    refuse_if_input(path, option, inputs);
    const std::string name = std::string(option) + " " + path;
    struct stat lst {};
    if (::lstat(path.c_str(), &lst) != 0) return;  // a new file
    if (S_ISDIR(lst.st_mode)) throw FileError(FileError::Kind::refused, name + " is a directory");
    if (S_ISLNK(lst.st_mode) && !system_path(path)) {
        std::error_code ec;
        const auto to = fs::read_symlink(path, ec);
        struct stat st {};
        if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
            throw FileError(FileError::Kind::refused, name + " is a directory");
        throw FileError(FileError::Kind::refused,
                        name + " is a symbolic link" + (ec ? "" : " (to " + to.string() + ")") +
                            "; ballbar does not write through links: give the file's real path");
    }
}

void check_distinct_outputs(const std::string& first, std::string_view first_option, const std::string& second,
                            std::string_view second_option) {
    if (first == "-" || second == "-" || first.empty() || second.empty()) return;
    bool same = false;
    struct stat a {
    }, b{};
    if (::stat(first.c_str(), &a) == 0 && ::stat(second.c_str(), &b) == 0) {
        same = a.st_dev == b.st_dev && a.st_ino == b.st_ino;
    } else {
        std::error_code ea, eb;
        const fs::path pa = fs::weakly_canonical(fs::absolute(first, ea), ea);
        const fs::path pb = fs::weakly_canonical(fs::absolute(second, eb), eb);
        same = !ea && !eb && pa == pb;
    }
    if (same)
        throw FileError(FileError::Kind::refused, std::string(second_option) + " " + second + " is the file of " +
                                                      std::string(first_option) +
                                                      ": one would overwrite the other (choose two files)");
}

OutputFile::OutputFile(std::string path, std::string option, const std::vector<Protected>& inputs)
    : path_(std::move(path)), option_(std::move(option)) {
    if (path_ == "-") {
        mode_ = Mode::stdout_;
        fd_ = STDOUT_FILENO;
        return;
    }
    if (path_.empty()) throw FileError(FileError::Kind::refused, option_ + ": empty file name");
    check_output(path_, option_, inputs);
    struct stat lst {};
    const bool exists = ::lstat(path_.c_str(), &lst) == 0;
    if (system_path(path_)) {
        // /dev/stdout when standard output is this very file: write through our own descriptor.
        struct stat st {
        }, out{};
        if (::stat(path_.c_str(), &st) == 0 && ::fstat(STDOUT_FILENO, &out) == 0 && st.st_dev == out.st_dev &&
            st.st_ino == out.st_ino) {
            mode_ = Mode::stdout_;
            fd_ = STDOUT_FILENO;
            return;
        }
        mode_ = Mode::direct;
    } else if (exists && !S_ISREG(lst.st_mode)) {
        mode_ = Mode::direct;  // a FIFO, a terminal, a device the operator named
    }
    if (mode_ == Mode::direct) {
        fd_ = ::open(path_.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC | O_APPEND);
        if (fd_ < 0) fail(path_, errno);
        return;
    }
    // A new or regular file: a temporary file of our own beside it, renamed over it by commit().
    const fs::path target(path_);
    const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
    mode_t mode = 0666;  // with the umask, as any new file
    if (exists) mode = lst.st_mode & 07777;
    for (int attempt = 0; attempt < 100 && fd_ < 0; ++attempt) {
        temp_ = (dir / (target.filename().string() + "." + random_suffix() + ".part")).string();
        fd_ = ::open(temp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, exists ? 0600 : mode);
        if (fd_ < 0 && errno != EEXIST) {
            const int e = errno;
            temp_.clear();
            if (e == ENOENT) throw FileError(FileError::Kind::failed, "cannot write " + path_ + ": no such directory");
            fail(path_, e);
        }
    }
    if (fd_ < 0) {
        temp_.clear();
        fail(path_, EEXIST);
    }
    if (exists) ::fchmod(fd_, mode);  // the target keeps its permissions
}

OutputFile::~OutputFile() {
    if (mode_ == Mode::stdout_) return;
    if (fd_ >= 0) ::close(fd_);
    if (!committed_ && !temp_.empty()) ::unlink(temp_.c_str());  // created by us, exclusively
}

void OutputFile::write(std::string_view bytes) {
    while (!bytes.empty()) {
        const ssize_t n = ::write(fd_, bytes.data(), bytes.size());
        if (n < 0) {
            if (errno == EINTR) continue;
            fail(path_ == "-" ? std::string("standard output") : path_, errno);
        }
        bytes.remove_prefix(static_cast<std::size_t>(n));
    }
}

void OutputFile::finish() {
    if (committed_ || mode_ != Mode::replace || fd_ < 0) return;
    if (::fsync(fd_) != 0) fail(path_, errno);
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail(path_, errno);
}

void OutputFile::commit() {
    if (committed_) return;
    if (mode_ == Mode::replace) {
        finish();
        if (::rename(temp_.c_str(), path_.c_str()) != 0) fail(path_, errno);
    }
    committed_ = true;
}

OutputStream::Buffer::Buffer(OutputFile& file) : file_(file), buf_(std::size_t{1} << 16, '\0') {
    setp(buf_.data(), buf_.data() + buf_.size());
}

void OutputStream::Buffer::drain() {
    const auto n = static_cast<std::size_t>(pptr() - pbase());
    setp(buf_.data(), buf_.data() + buf_.size());  // emptied even when the write throws
    if (n > 0) file_.write(std::string_view(buf_.data(), n));
}

OutputStream::Buffer::int_type OutputStream::Buffer::overflow(int_type c) {
    drain();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
        *pptr() = traits_type::to_char_type(c);
        pbump(1);
    }
    return traits_type::not_eof(c);
}

int OutputStream::Buffer::sync() {
    drain();
    return 0;
}

OutputStream::OutputStream(std::string path, std::string option, const std::vector<Protected>& inputs)
    : std::ostream(nullptr), file_(std::move(path), std::move(option), inputs), buffer_(file_) {
    rdbuf(&buffer_);
    exceptions(std::ios::badbit);  // the FileError of a failed write reaches the caller
}

void OutputStream::finish() {
    buffer_.drain();
    file_.finish();
}

void OutputStream::commit() {
    buffer_.drain();
    file_.commit();
}

void write_file(const std::string& path, std::string_view option, std::string_view bytes,
                const std::vector<Protected>& inputs) {
    OutputFile out(path, std::string(option), inputs);
    out.write(bytes);
    out.commit();
}

}  // namespace ballbar::fileio
