// foveal/util/cpu_share.cpp — the kernel's CPU counters around a timed run.
#include "foveal/util/cpu_share.h"

#include "foveal/util/error.h"
#include "foveal/util/text.h"

#include <algorithm>
#include <optional>
#include <string>
#include <vector>

namespace foveal {

namespace {

// The first line of `text`, as whitespace-separated fields.
std::vector<std::string_view> first_line_fields(std::string_view text) { return text::split(text.substr(0, text.find('\n')), ' '); }

// A counter: a whole non-negative number.
std::optional<double> counter(std::string_view field) {
  const std::optional<double> v = text::to_number(field);
  return v && *v >= 0 ? v : std::nullopt;
}

std::string read_or_empty(const char* path) {
  try {
    return text::read_file(path);
  } catch (const Error&) {
    return {};
  }
}

}  // namespace

CpuTimes parse_cpu_times(std::string_view proc_stat, std::string_view self_stat) {
  CpuTimes t;
  // /proc/stat's first line: "cpu  user nice system idle iowait irq softirq steal guest guest_nice"
  // (guest time is counted in user already)
  const std::vector<std::string_view> cpu = first_line_fields(proc_stat);
  if (cpu.size() < 9 || cpu[0] != "cpu") return t;
  double f[8];
  for (size_t k = 0; k < 8; ++k) {
    const std::optional<double> v = counter(cpu[k + 1]);
    if (!v) return t;
    f[k] = *v;
  }
  const double user = f[0], nice = f[1], system = f[2], idle = f[3], iowait = f[4], irq = f[5], softirq = f[6], steal = f[7];
  // /proc/self/stat: "pid (comm) state ppid …", utime and stime the 14th and 15th fields; the
  // command may hold spaces and parentheses, so fields are counted from its last ')' (the state,
  // field 3, is the first after it)
  const size_t close = self_stat.rfind(')');
  if (close == std::string_view::npos) return t;
  const std::vector<std::string_view> fields = first_line_fields(self_stat.substr(close + 1));
  if (fields.size() < 13) return t;
  const std::optional<double> utime = counter(fields[11]), stime = counter(fields[12]);
  if (!utime || !stime) return t;
  t.total = user + nice + system + idle + iowait + irq + softirq + steal;
  t.busy = user + nice + system + irq + softirq;
  t.steal = steal;
  t.self = *utime + *stime;
  t.known = true;
  return t;
}

CpuTimes read_cpu_times() { return parse_cpu_times(read_or_empty("/proc/stat"), read_or_empty("/proc/self/stat")); }

CpuShare cpu_share(const CpuTimes& before, const CpuTimes& after) {
  CpuShare s;
  const double total = after.total - before.total;
  if (!before.known || !after.known || !(total > 0)) return s;
  const double others = (after.busy - before.busy) - (after.self - before.self);
  s.others = std::clamp(others / total, 0.0, 1.0);
  s.steal = std::clamp((after.steal - before.steal) / total, 0.0, 1.0);
  return s;
}

}  // namespace foveal
