// foveal/util/kernel_info.cpp — the kernel's tick and preemption model from its config.
#include "foveal/util/kernel_info.h"

#include "foveal/util/gzip.h"
#include "foveal/util/text.h"

#include <fmt/format.h>

#include <charconv>
#include <filesystem>

#include <sys/utsname.h>

namespace foveal {

namespace {

// The value of `NAME=` in a config text ("" where absent or "is not set")
std::string_view config_value(std::string_view config, std::string_view name) {
  for (const std::string_view line : text::split(config, '\n'))
    if (line.size() > name.size() && line.starts_with(name) && line[name.size()] == '=') return line.substr(name.size() + 1);
  return {};
}

bool config_set(std::string_view config, std::string_view name) { return config_value(config, name) == "y"; }

bool known_mode(std::string_view m) { return m == "none" || m == "voluntary" || m == "full" || m == "lazy"; }

}  // namespace

KernelScheduling parse_kernel_scheduling(std::string_view config, std::string_view cmdline, std::string_view debugfs_preempt) {
  KernelScheduling k;
  const std::string_view hz = config_value(config, "CONFIG_HZ");
  int v = 0;
  if (!hz.empty() && std::from_chars(hz.data(), hz.data() + hz.size(), v).ec == std::errc() && v > 0 && v <= 10000) k.hz = v;
  if (config_set(config, "CONFIG_PREEMPT_RT")) {
    k.preempt = "rt";
    return k;
  }
  // debugfs marks the mode in force: "none voluntary (full) lazy"
  const size_t open = debugfs_preempt.find('('), close = debugfs_preempt.find(')');
  if (open != std::string_view::npos && close != std::string_view::npos && close > open) {
    const std::string_view m = debugfs_preempt.substr(open + 1, close - open - 1);
    if (known_mode(m)) {
      k.preempt = std::string(m);
      k.source = "/sys/kernel/debug/sched/preempt";
      return k;
    }
  }
  if (config_set(config, "CONFIG_PREEMPT_DYNAMIC")) {
    for (const std::string_view word : text::split(cmdline, ' ')) {
      std::string_view w = text::trim(word);
      if (w.starts_with("preempt=") && known_mode(w.substr(8))) {
        k.preempt = std::string(w.substr(8));
        k.source = "/proc/cmdline";
        return k;
      }
    }
  }
  if (config_set(config, "CONFIG_PREEMPT_NONE"))
    k.preempt = "none";
  else if (config_set(config, "CONFIG_PREEMPT_VOLUNTARY"))
    k.preempt = "voluntary";
  else if (config_set(config, "CONFIG_PREEMPT_LAZY"))
    k.preempt = "lazy";
  else if (config_set(config, "CONFIG_PREEMPT"))
    k.preempt = "full";
  return k;
}

KernelScheduling read_kernel_scheduling() {
  utsname u{};
  const std::string release = uname(&u) == 0 ? std::string(u.release) : std::string();
  // The config: the running kernel's own, else the one installed beside it (Debian, Ubuntu, Fedora)
  std::string config, source;
  for (const std::string& path : {std::string("/proc/config.gz"), release.empty() ? std::string() : "/boot/config-" + release}) {
    std::error_code ec;
    if (path.empty() || !std::filesystem::is_regular_file(path, ec)) continue;
    try {
      config = read_gzip_file(path, size_t(1) << 24);  // (a plain file is read as it is)
      source = path;
      break;
    } catch (const std::exception&) {
      config.clear();
    }
  }
  KernelScheduling k = parse_kernel_scheduling(config, text::read_file_or_empty("/proc/cmdline", 1 << 16),
                                               text::read_file_or_empty("/sys/kernel/debug/sched/preempt", 1 << 16));
  k.release = release;
  // The config's file, and the one that chose the preemption model where another did
  if (!k.source.empty() && !source.empty()) source += ", ";
  k.source = source + k.source;
  return k;
}

std::string kernel_phrase(const KernelScheduling& k) {
  if (k.hz <= 0) return {};
  return fmt::format("the kernel{} ticks at {} Hz{}{}", k.release.empty() ? "" : fmt::format(" ({})", k.release), k.hz,
                     k.preempt.empty() ? "" : fmt::format(", preemption {}", k.preempt),
                     k.source.empty() ? "" : fmt::format(" ({})", k.source));
}

}  // namespace foveal
