// SPDX-License-Identifier: MIT
// A device node the user may not open (no udev rules) must give DeviceError{Permission} with a message
// that says how to install the rules. Nodes get mode 0600 (root-owned, as without our rules); as root,
// where modes do not apply, the open runs in a child process that has dropped to user "nobody".
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>

#include "ballbar/device/hid.hpp"
#include "ballbar/device/ids.hpp"
#include "ballbar/device/usb.hpp"
#include "fake_hid_device.hpp"
#include "fake_usb_device.hpp"

namespace ballbar::device::testing {
namespace {

constexpr uid_t kNobody = 65534;

/// Child exit codes.
enum : int { kGotPermission = 10, kGotOtherError = 11, kOpened = 12, kBadHint = 13, kSetuidFailed = 14 };

int classify(const std::function<void()>& open) {
    try {
        open();
        return kOpened;
    } catch (const DeviceError& e) {
        if (e.kind() != DeviceErrorKind::Permission) {
            std::fprintf(stderr, "child: %s: %s\n", to_string(e.kind()), e.what());
            return kGotOtherError;
        }
        const std::string msg = e.what();
        const bool hint = msg.find("udev rules") != std::string::npos &&
                          msg.find("cmake --install") != std::string::npos &&
                          msg.find("udevadm control --reload") != std::string::npos &&
                          msg.find("udevadm trigger") != std::string::npos;
        return hint ? kGotPermission : kBadHint;
    }
}

/// Runs `open` without the right to open root's 0600 nodes; returns the classification.
int open_unprivileged(const std::function<void()>& open) {
    if (geteuid() != 0) return classify(open);
    const pid_t pid = fork();
    if (pid == 0) {
        if (setgid(kNobody) != 0 || setuid(kNobody) != 0) _exit(kSetuidFailed);
        _exit(classify(open));
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class Permission : public ::testing::Test {
  protected:
    void SetUp() override {
        if (!Testbed::preload_active()) GTEST_SKIP() << "needs LD_PRELOAD=libumockdev-preload.so.0";
        tb_ = std::make_unique<Testbed>();
        gchar* root = umockdev_testbed_get_root_dir(tb_->get());
        root_ = root;
        g_free(root);
    }
    void TearDown() override {
        hid_.reset();
        usb_.reset();
        tb_.reset();
    }
    /// Makes the node behind `dev_path` (and what a symlink points to) root-only, as without our rules.
    void restrict_node(const std::string& dev_path) {
        if (geteuid() == 0) {
            // "nobody" must be able to walk umockdev's sysfs and /dev and reach its ioctl sockets (the
            // testbed is a private temporary directory), so only the node itself stops it
            namespace fs = std::filesystem;
            fs::permissions(root_, fs::perms::all, fs::perm_options::add);
            for (const auto& e : fs::recursive_directory_iterator(root_)) {
                if (!e.is_symlink()) fs::permissions(e.path(), fs::perms::all, fs::perm_options::add);
            }
        }
        const std::string node = root_ + dev_path;
        ASSERT_EQ(chmod(node.c_str(), 0600), 0) << node;
        if (geteuid() != 0) {
            ASSERT_EQ(chmod(node.c_str(), 0000), 0) << node;
        }
    }
    EchoEndpoint echo_;
    std::unique_ptr<Testbed> tb_;
    std::string root_;
    std::unique_ptr<FakeUsbBulkDevice> usb_;
    std::unique_ptr<FakeHidDevice> hid_;
};

TEST_F(Permission, UsbNodeWithoutRulesSaysHowToInstallThem) {
    usb_ = std::make_unique<FakeUsbBulkDevice>(*tb_, echo_, kBallbarVendorId, kBallbarBulkProductId, "BB0001");
    usb_->plug();
    restrict_node(usb_->node());
    EXPECT_EQ(open_unprivileged([] { open_usb_transport(kBallbarVendorId, kBallbarBulkProductId, ""); }),
              kGotPermission);
}

TEST_F(Permission, HidrawNodeWithoutRulesSaysHowToInstallThem) {
    hid_ = std::make_unique<FakeHidDevice>(*tb_, echo_, kBallbarVendorId, kBallbarHidProductId, "BB0002");
    hid_->plug();
    restrict_node(hid_->node());
    EXPECT_EQ(open_unprivileged([] { open_hid_transport(kBallbarVendorId, kBallbarHidProductId, ""); }),
              kGotPermission);
}

TEST(PermissionHint, NamesTheNodeAndTheInstallSteps) {
    const std::string m = udev_permission_hint("/dev/hidraw3");
    EXPECT_NE(m.find("/dev/hidraw3"), std::string::npos);
    EXPECT_NE(m.find("udev rules"), std::string::npos);
    EXPECT_NE(m.find("sudo cmake --install build"), std::string::npos);
    EXPECT_NE(m.find("sudo udevadm control --reload && sudo udevadm trigger"), std::string::npos);
}

}  // namespace
}  // namespace ballbar::device::testing
