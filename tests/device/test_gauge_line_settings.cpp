// SPDX-License-Identifier: MIT
// The serial line settings each gauge driver asks for (docs/instruments.md): Sylvac 4800 7E2, the
// Digimatic adaptor 9600 8N1, Modbus 38400 8N2 (and the URI's baud=). Each driver opens a real pty
// through its real code path (the serial transport, libmodbus) and the test reads the line back.
//
// What a Linux pty keeps: the baud rate, CSTOPB, CLOCAL/CREAD, CRTSCTS and the raw-mode flags, on both
// sides (tcgetattr on the master reports its slave's termios). What it does not keep: the kernel's
// pty_set_termios() forces CS8 and clears PARENB on every tcsetattr, so 7 data bits and parity cannot be
// read back from a pty. For those the test binary interposes tcsetattr(3) (a definition in the
// executable wins over libc's for libmodbus too) and checks what the driver *asked for*; where the pty
// does keep a flag, the request and the pty must agree, so the record is the real request.
#include <dlfcn.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <mutex>
#include <optional>
#include <string>

#include "ballbar/device/emulator_host.hpp"
#include "ballbar/device/gauge.hpp"

namespace {

std::mutex g_mutex;
struct Request {
    dev_t rdev = 0;  ///< the terminal it was made on
    termios t{};
};
std::optional<Request> g_last;

}  // namespace

extern "C" __attribute__((visibility("default"))) int tcsetattr(int fd, int action, const termios* t) {
    using Fn = int (*)(int, int, const termios*);
    static const Fn real = reinterpret_cast<Fn>(dlsym(RTLD_NEXT, "tcsetattr"));
    struct stat st {};
    if (t && ::fstat(fd, &st) == 0) {
        std::lock_guard lock(g_mutex);
        g_last = Request{st.st_rdev, *t};
    }
    return real(fd, action, t);
}

namespace ballbar::device::gauge {
namespace {

struct Line {
    speed_t speed;
    tcflag_t csize;
    bool parity, odd, two_stop;
};

/// What the driver asked for on the pty's slave, and what the pty holds (master side and slave side).
struct Observed {
    termios requested{}, master{}, slave{};
};

Observed open_and_observe(const std::string& uri_prefix, const std::string& uri_suffix = "") {
    PseudoTerminal pty;
    {
        std::lock_guard lock(g_mutex);
        g_last.reset();
    }
    const auto gauge = open_gauge(uri_prefix + pty.path() + uri_suffix);
    Observed o;
    struct stat st {};
    EXPECT_EQ(::stat(pty.path().c_str(), &st), 0);
    {
        std::lock_guard lock(g_mutex);
        EXPECT_TRUE(g_last.has_value()) << "the driver never called tcsetattr";
        if (g_last) {
            EXPECT_EQ(g_last->rdev, st.st_rdev) << "the last tcsetattr was not on the gauge's port";
            o.requested = g_last->t;
        }
    }
    EXPECT_EQ(::tcgetattr(pty.master(), &o.master), 0);
    const int slave = ::open(pty.path().c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    EXPECT_GE(slave, 0);
    EXPECT_EQ(::tcgetattr(slave, &o.slave), 0);
    ::close(slave);
    return o;
}

void expect_line(const Observed& o, const Line& want) {
    const termios& r = o.requested;
    EXPECT_EQ(cfgetospeed(&r), want.speed);
    EXPECT_EQ(cfgetispeed(&r), want.speed);
    EXPECT_EQ(r.c_cflag & CSIZE, want.csize);
    EXPECT_EQ((r.c_cflag & PARENB) != 0, want.parity);
    if (want.parity) {
        EXPECT_EQ((r.c_cflag & PARODD) != 0, want.odd);
    }
    EXPECT_EQ((r.c_cflag & CSTOPB) != 0, want.two_stop);
    EXPECT_EQ(r.c_cflag & CRTSCTS, 0u) << "no hardware flow control";
    EXPECT_NE(r.c_cflag & CLOCAL, 0u);
    EXPECT_NE(r.c_cflag & CREAD, 0u);
    EXPECT_EQ(r.c_lflag & (ICANON | ECHO | ISIG), 0u) << "raw mode";
    EXPECT_EQ(r.c_iflag & (IXON | IXOFF | ICRNL | INLCR), 0u) << "no software flow control, no CR/LF mapping";
    EXPECT_EQ(r.c_oflag & OPOST, 0u);
    for (const termios* side : {&o.master, &o.slave}) {
        const char* name = side == &o.master ? "master" : "slave";
        // What the pty keeps must be what was asked for.
        EXPECT_EQ(cfgetospeed(side), want.speed) << name;
        EXPECT_EQ(cfgetispeed(side), want.speed) << name;
        EXPECT_EQ((side->c_cflag & CSTOPB) != 0, want.two_stop) << name;
        EXPECT_EQ(side->c_cflag & CRTSCTS, 0u) << name;
        EXPECT_EQ(side->c_lflag & (ICANON | ECHO | ISIG), 0u) << name;
        EXPECT_EQ(side->c_iflag & (IXON | IXOFF | ICRNL | INLCR), 0u) << name;
        // The kernel forces CS8 without parity on a pty; another kernel that keeps them must keep ours.
        if ((side->c_cflag & CSIZE) != CS8 || (side->c_cflag & PARENB)) {
            EXPECT_EQ(side->c_cflag & CSIZE, want.csize) << name;
            EXPECT_EQ((side->c_cflag & PARENB) != 0, want.parity) << name;
        }
    }
}

TEST(GaugeLineSettings, SylvacIs4800Baud7DataBitsEvenParity2StopBits) {
    expect_line(open_and_observe("sylvac:"), {B4800, CS7, true, false, true});
}

TEST(GaugeLineSettings, SylvacUriParametersDoNotChangeTheLine) {
    expect_line(open_and_observe("sylvac:", "?sign=-1&rate=25"), {B4800, CS7, true, false, true});
}

// The second open of the same pty (a reconnect, the next `measure` on one `emulate`): Linux refuses a
// request for 7 bits and parity once the pty holds the 8N it forces (EINVAL); the transport asks again
// for what a pty keeps, and the line stays 4800 baud with 2 stop bits.
TEST(GaugeLineSettings, SylvacOpensTheSamePtyAgainAndAgain) {
    PseudoTerminal pty;
    for (int i = 0; i < 4; ++i) {
        SCOPED_TRACE("open " + std::to_string(i + 1));
        EXPECT_NO_THROW((void)open_gauge("sylvac:" + pty.path()));
    }
    termios m{};
    ASSERT_EQ(::tcgetattr(pty.master(), &m), 0);
    EXPECT_EQ(cfgetospeed(&m), static_cast<speed_t>(B4800));
    EXPECT_NE(m.c_cflag & CSTOPB, 0u);
    EXPECT_EQ(m.c_lflag & (ICANON | ECHO | ISIG), 0u);
}

TEST(GaugeLineSettings, DigimaticAdaptorIs9600Baud8N1) {
    expect_line(open_and_observe("digimatic:"), {B9600, CS8, false, false, false});
}

TEST(GaugeLineSettings, ModbusIs38400Baud8N2ByDefault) {
    expect_line(open_and_observe("modbus:"), {B38400, CS8, false, false, true});
}

TEST(GaugeLineSettings, ModbusHonoursTheBaudOfTheUri) {
    expect_line(open_and_observe("modbus:", "?slave=7&baud=9600"), {B9600, CS8, false, false, true});
    expect_line(open_and_observe("modbus:", "?baud=115200"), {B115200, CS8, false, false, true});
}

}  // namespace
}  // namespace ballbar::device::gauge
