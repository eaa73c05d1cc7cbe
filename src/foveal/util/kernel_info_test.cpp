// The kernel's tick and preemption model, from the texts Linux states them in.
#include "foveal/util/kernel_info.h"

#include <gtest/gtest.h>

#include <sys/utsname.h>

using namespace foveal;

namespace {
// A config as a kernel build writes it (the lines that matter, among others)
const char* kDebianLike =
    "#\n# Automatically generated file; DO NOT EDIT.\nCONFIG_HZ_250=y\nCONFIG_HZ=250\n# CONFIG_PREEMPT_NONE is not set\n"
    "CONFIG_PREEMPT_VOLUNTARY=y\n# CONFIG_PREEMPT is not set\nCONFIG_PREEMPT_DYNAMIC=y\nCONFIG_PREEMPT_RCU=y\n";
}  // namespace

TEST(KernelInfo, TheTickAndTheConfigsPreemption) {
  const KernelScheduling k = parse_kernel_scheduling(kDebianLike, "BOOT_IMAGE=/vmlinuz root=/dev/sda1 quiet", "");
  EXPECT_EQ(k.hz, 250);
  EXPECT_EQ(k.preempt, "voluntary");  // CONFIG_PREEMPT_RCU and CONFIG_PREEMPT_DYNAMIC are no model
  EXPECT_EQ(parse_kernel_scheduling("CONFIG_HZ=1000\nCONFIG_PREEMPT=y\n", "", "").preempt, "full");
  EXPECT_EQ(parse_kernel_scheduling("CONFIG_HZ=1000\nCONFIG_PREEMPT=y\n", "", "").hz, 1000);
  EXPECT_EQ(parse_kernel_scheduling("CONFIG_PREEMPT_NONE=y\nCONFIG_HZ=100\n", "", "").preempt, "none");
  EXPECT_EQ(parse_kernel_scheduling("CONFIG_PREEMPT_LAZY=y\n", "", "").preempt, "lazy");
  // PREEMPT_RT whatever else is set
  EXPECT_EQ(parse_kernel_scheduling("CONFIG_PREEMPT=y\nCONFIG_PREEMPT_RT=y\nCONFIG_HZ=1000\n", "preempt=none", "").preempt, "rt");
}

TEST(KernelInfo, TheBootLineAndDebugfsOverrideADynamicKernelsDefault) {
  const KernelScheduling boot = parse_kernel_scheduling(kDebianLike, "root=/dev/sda1 preempt=full quiet\n", "");
  EXPECT_EQ(boot.preempt, "full");
  EXPECT_EQ(boot.source, "/proc/cmdline");
  // debugfs marks the mode in force (it may have been changed since boot)
  const KernelScheduling debugfs = parse_kernel_scheduling(kDebianLike, "preempt=full", "none voluntary full (lazy)\n");
  EXPECT_EQ(debugfs.preempt, "lazy");
  EXPECT_EQ(debugfs.source, "/sys/kernel/debug/sched/preempt");
  EXPECT_EQ(parse_kernel_scheduling(kDebianLike, "", "").source, "");  // (the config's own file is the reader's to name)
  // Without PREEMPT_DYNAMIC the boot line's word means nothing
  EXPECT_EQ(parse_kernel_scheduling("CONFIG_PREEMPT_NONE=y\n", "preempt=full", "").preempt, "none");
  // An unknown mode is not taken
  EXPECT_EQ(parse_kernel_scheduling(kDebianLike, "preempt=fast", "").preempt, "voluntary");
}

TEST(KernelInfo, NothingStatedLeavesTheFieldsEmpty) {
  for (const char* config : {"", "CONFIG_HZ=\n", "CONFIG_HZ=abc\n", "CONFIG_HZ=-5\n", "CONFIG_HZ_1000=y\n", "CONFIG_HZX=100\n"}) {
    const KernelScheduling k = parse_kernel_scheduling(config, "", "");
    EXPECT_EQ(k.hz, 0) << config;
    EXPECT_EQ(k.preempt, "") << config;
  }
  EXPECT_EQ(kernel_phrase(KernelScheduling{}), "");
  KernelScheduling k;
  k.hz = 250;
  k.preempt = "none";
  k.release = "6.18.44";
  k.source = "/proc/config.gz";
  EXPECT_EQ(kernel_phrase(k), "the kernel (6.18.44) ticks at 250 Hz, preemption none (/proc/config.gz)");
}

TEST(KernelInfo, ThisMachinesReleaseIsUnames) {
  utsname u{};
  ASSERT_EQ(uname(&u), 0);
  const KernelScheduling k = read_kernel_scheduling();
  EXPECT_EQ(k.release, u.release);
  if (k.hz > 0) {  // where the config was found, it says where
    EXPECT_FALSE(k.source.empty());
    EXPECT_GE(k.hz, 24);
  }
}
