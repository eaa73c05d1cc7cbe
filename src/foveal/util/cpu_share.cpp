// foveal/util/cpu_share.cpp — the kernel's CPU counters around a timed run.
#include "foveal/util/cpu_share.h"

#include "foveal/util/error.h"
#include "foveal/util/text.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <sys/resource.h>

#ifdef __linux__
#include <sys/syscall.h>
#include <unistd.h>
#endif

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

std::optional<ThreadTime> parse_schedstat(std::string_view schedstat) {
  const std::vector<std::string_view> f = first_line_fields(schedstat);
  if (f.size() < 2) return std::nullopt;
  const std::optional<double> run = counter(f[0]), wait = counter(f[1]);
  if (!run || !wait) return std::nullopt;
  return ThreadTime{*run, *wait};
}

ThreadTimes read_thread_times() {
  ThreadTimes times;
  // Stepped with an error code, never throwing: a listing that fails part-way gives the threads read
  std::error_code ec;
  for (std::filesystem::directory_iterator it("/proc/self/task", ec), end; !ec && it != end; it.increment(ec)) {
    const std::filesystem::path& dir = it->path();
    const std::optional<double> tid = text::to_number(dir.filename().string());
    if (!tid) continue;
    // A thread that ended since the listing has no file: left out
    if (const std::optional<ThreadTime> t = parse_schedstat(read_or_empty((dir / "schedstat").c_str())))
      times[static_cast<long>(*tid)] = *t;
  }
  return times;
}

namespace {

// Over the threads in both readings: combine(so far, the thread's change in `field`, ms)
template <typename Combine>
double over_threads(const ThreadTimes& before, const ThreadTimes& after, double ThreadTime::*field, Combine combine, long only = -1) {
  double out = NAN;
  for (const auto& [tid, t] : after) {
    const auto b = before.find(tid);
    if (b == before.end() || (only >= 0 && tid != only)) continue;
    const double ms = std::max(0.0, t.*field - b->second.*field) / 1e6;
    out = std::isnan(out) ? ms : combine(out, ms);
  }
  return out;
}

}  // namespace

double longest_wait_ms(const ThreadTimes& before, const ThreadTimes& after) {
  return over_threads(before, after, &ThreadTime::wait_ns, [](double a, double b) { return std::max(a, b); });
}

double cpu_ms(const ThreadTimes& before, const ThreadTimes& after, long only) {
  return over_threads(
      before, after, &ThreadTime::run_ns, [](double a, double b) { return a + b; }, only);
}

double page_faults() {
  rusage u{};
  if (getrusage(RUSAGE_SELF, &u) != 0) return NAN;
  return static_cast<double>(u.ru_minflt) + static_cast<double>(u.ru_majflt);
}

long current_thread_id() {
#ifdef __linux__
  return static_cast<long>(::syscall(SYS_gettid));
#else
  return -1;
#endif
}

}  // namespace foveal
