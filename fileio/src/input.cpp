// SPDX-License-Identifier: MIT
#include "ballbar/fileio/input.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace ballbar::fileio {
namespace {

std::string kind_of(mode_t mode) {
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISCHR(mode)) return "a character device";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISSOCK(mode)) return "a socket";
    return "not a regular file";
}

std::string mib(std::size_t bytes) {
    return std::to_string(bytes >> 20) + " MiB";
}

[[noreturn]] void refuse_too_large(const InputFile& f, std::size_t max_bytes, const std::string& size) {
    throw FileError(FileError::Kind::refused, "the " + f.what() + " " + f.path() + " is too large (" + size +
                                                  "; at most " + mib(max_bytes) + " are read)");
}

}  // namespace

std::string cut(std::string_view text, std::size_t max_chars) {
    if (text.size() <= max_chars) return std::string(text);
    std::size_t n = max_chars;
    while (n > 0 && (static_cast<unsigned char>(text[n]) & 0xC0) == 0x80) --n;  // not inside a UTF-8 character
    return std::string(text.substr(0, n)) + "…";
}

InputFile InputFile::open(const std::string& path, std::string_view what) {
    const std::string w(what);
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
    if (fd < 0) {
        const int e = errno;
        if (e == ENOENT) throw FileError(FileError::Kind::refused, "no such " + w + ": " + path);
        throw FileError(FileError::Kind::refused, "cannot read the " + w + " " + path + ": " + std::strerror(e));
    }
    InputFile f(fd, true, path, w, 0);
    struct stat st {};
    if (::fstat(fd, &st) != 0)
        throw FileError(FileError::Kind::failed, "cannot read the " + w + " " + path + ": " + std::strerror(errno));
    if (S_ISDIR(st.st_mode)) throw FileError(FileError::Kind::refused, "the " + w + " " + path + " is a directory");
    if (!S_ISREG(st.st_mode)) {
        throw FileError(FileError::Kind::refused,
                        "the " + w + " " + path + " is " + kind_of(st.st_mode) + ", not a regular file");
    }
    f.size_ = static_cast<std::uint64_t>(st.st_size);
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    return f;
}

InputFile InputFile::standard_input(std::string_view what) {
    struct stat st {};
    std::uint64_t size = 0;
    if (::fstat(STDIN_FILENO, &st) == 0) {
        if (S_ISDIR(st.st_mode))
            throw FileError(FileError::Kind::refused, "standard input (the " + std::string(what) + ") is a directory");
        if (S_ISREG(st.st_mode)) size = static_cast<std::uint64_t>(st.st_size);
    }
    return InputFile(STDIN_FILENO, false, "(standard input)", std::string(what), size);
}

InputFile::InputFile(InputFile&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      owned_(other.owned_),
      path_(std::move(other.path_)),
      what_(std::move(other.what_)),
      size_(other.size_) {}

InputFile& InputFile::operator=(InputFile&& other) noexcept {
    if (this != &other) {
        if (owned_ && fd_ >= 0) ::close(fd_);
        fd_ = std::exchange(other.fd_, -1);
        owned_ = other.owned_;
        path_ = std::move(other.path_);
        what_ = std::move(other.what_);
        size_ = other.size_;
    }
    return *this;
}

InputFile::~InputFile() {
    if (owned_ && fd_ >= 0) ::close(fd_);
}

std::size_t InputFile::read(char* buf, std::size_t n) {
    while (true) {
        const ssize_t got = ::read(fd_, buf, n);
        if (got >= 0) return static_cast<std::size_t>(got);
        if (errno == EINTR) continue;
        const int e = errno;
        if (e == EISDIR) throw FileError(FileError::Kind::refused, "the " + what_ + " " + path_ + " is a directory");
        throw FileError(FileError::Kind::failed, "cannot read the " + what_ + " " + path_ + ": " + std::strerror(e));
    }
}

std::string read_whole(InputFile& file, std::size_t max_bytes) {
    if (file.size() > max_bytes) refuse_too_large(file, max_bytes, std::to_string(file.size()) + " bytes");
    std::string text;
    text.resize(static_cast<std::size_t>(file.size()) + 1);  // +1: see the end in one read
    std::size_t used = 0;
    while (true) {
        if (used == text.size()) {
            if (used > max_bytes) refuse_too_large(file, max_bytes, "more than that");
            text.resize(std::min(std::max<std::size_t>(2 * used, 4096), max_bytes + 1));
        }
        const std::size_t got = file.read(text.data() + used, text.size() - used);
        if (got == 0) break;
        used += got;
        if (used > max_bytes) refuse_too_large(file, max_bytes, "more than that");
    }
    text.resize(used);
    return text;
}

std::string read_whole(const std::string& path, std::string_view what, std::size_t max_bytes) {
    InputFile f = InputFile::open(path, what);
    return read_whole(f, max_bytes);
}

void check_json_nesting(std::string_view text, std::string_view what, int max_depth, std::size_t max_values) {
    int depth = 0;
    bool in_string = false, escaped = false;
    std::size_t values = 1;  // the top-level one; each ',' and each '[' or '{' adds one (an upper bound)
    auto count = [&](std::size_t i) {
        if (++values > max_values)
            throw FileError(FileError::Kind::refused, std::string(what) + ": JSON with more than " +
                                                          std::to_string(max_values) + " values (at byte " +
                                                          std::to_string(i + 1) + ")");
    };
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (in_string) {
            if (escaped)
                escaped = false;
            else if (c == '\\')
                escaped = true;
            else if (c == '"')
                in_string = false;
        } else if (c == '"') {
            in_string = true;
        } else if (c == ',') {
            count(i);
        } else if (c == '[' || c == '{') {
            count(i);
            if (++depth > max_depth)
                throw FileError(FileError::Kind::refused, std::string(what) + ": JSON nested deeper than " +
                                                              std::to_string(max_depth) + " levels (at byte " +
                                                              std::to_string(i + 1) + ")");
        } else if ((c == ']' || c == '}') && depth > 0) {
            --depth;
        }
    }
}

std::string read_json(const std::string& path, std::string_view what) {
    std::string text = read_whole(path, what, kMaxJsonBytes);
    check_json_nesting(text, what);
    return text;
}

std::string read_text(const std::string& path, std::string_view what, std::size_t max_bytes, std::size_t max_line) {
    std::string text = read_whole(path, what, max_bytes);
    std::size_t start = 0;
    std::uint64_t line = 1;
    while (start < text.size()) {
        const char* nl = static_cast<const char*>(std::memchr(text.data() + start, '\n', text.size() - start));
        const std::size_t stop = nl ? static_cast<std::size_t>(nl - text.data()) : text.size();
        std::size_t length = stop - start;
        if (length > 0 && text[stop - 1] == '\r') --length;  // CRLF
        if (length > max_line) {
            throw FileError(FileError::Kind::refused, "the " + std::string(what) + " " + path + ": line " +
                                                          std::to_string(line) + " is longer than " +
                                                          std::to_string(max_line) + " bytes");
        }
        start = stop + 1;
        ++line;
    }
    return text;
}

std::string read_head(const std::string& path, std::string_view what, std::size_t n) {
    InputFile f = InputFile::open(path, what);
    std::string head(n, '\0');
    std::size_t used = 0;
    while (used < n) {
        const std::size_t got = f.read(head.data() + used, n - used);
        if (got == 0) break;
        used += got;
    }
    head.resize(used);
    return head;
}

LineReader::LineReader(InputFile file, std::size_t max_line) : file_(std::move(file)), max_line_(max_line) {
    buf_.resize(std::max<std::size_t>(std::min<std::size_t>(max_line_ + 2, std::size_t{1} << 16), 64));
}

bool LineReader::fill() {
    if (eof_) return false;
    if (begin_ > 0) {  // keep the partial line at the front
        std::memmove(buf_.data(), buf_.data() + begin_, end_ - begin_);
        end_ -= begin_;
        begin_ = 0;
    }
    if (end_ == buf_.size() && buf_.size() < max_line_ + 2) buf_.resize(std::min(2 * buf_.size(), max_line_ + 2));
    const std::size_t got = file_.read(buf_.data() + end_, buf_.size() - end_);
    if (got == 0) {
        eof_ = true;
        return false;
    }
    if (tap_) tap_(std::string_view(buf_.data() + end_, got));
    end_ += got;
    return true;
}

std::optional<std::string_view> LineReader::next() {
    std::size_t scanned = begin_;
    const std::uint64_t number = line_ + 1;
    while (true) {
        const char* nl = static_cast<const char*>(std::memchr(buf_.data() + scanned, '\n', end_ - scanned));
        if (nl) {
            const std::size_t stop = static_cast<std::size_t>(nl - buf_.data());
            std::string_view line(buf_.data() + begin_, stop - begin_);
            begin_ = stop + 1;
            ++line_;
            if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
            if (line.size() > max_line_) break;
            return line;
        }
        if (end_ - begin_ > max_line_ + 1) break;  // +1: a CR before the LF
        const std::size_t before = end_ - begin_;
        if (!fill()) {
            if (end_ == begin_) return std::nullopt;
            std::string_view line(buf_.data() + begin_, end_ - begin_);  // the last line, without LF
            begin_ = end_;
            ++line_;
            if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
            if (line.size() > max_line_) break;
            return line;
        }
        scanned = begin_ + before;
    }
    throw FileError(FileError::Kind::refused, "the " + file_.what() + " " + file_.path() + ": line " +
                                                  std::to_string(number) + " is longer than " +
                                                  std::to_string(max_line_) + " bytes (is it a " + file_.what() + "?)");
}

}  // namespace ballbar::fileio
