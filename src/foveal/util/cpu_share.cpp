// foveal/util/cpu_share.cpp — the kernel's CPU counters around a timed run.
#include "foveal/util/cpu_share.h"

#include "foveal/util/error.h"
#include "foveal/util/text.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
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

CpuTimes read_cpu_times() { return parse_cpu_times(text::read_file_or_empty("/proc/stat"), text::read_file_or_empty("/proc/self/stat")); }

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
  const std::optional<double> slices = f.size() >= 3 ? counter(f[2]) : std::optional<double>(0.0);
  if (!slices) return std::nullopt;
  return ThreadTime{*run, *wait, *slices};
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
    if (const std::optional<ThreadTime> t = parse_schedstat(text::read_file_or_empty((dir / "schedstat").c_str())))
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

std::optional<bool> parse_kernel_thread(std::string_view stat) {
  // "pid (comm) state ppid pgrp session tty_nr tpgid flags …": the flags are the seventh field
  // after the command's last ')'
  const size_t close = stat.rfind(')');
  if (close == std::string_view::npos) return std::nullopt;
  const std::vector<std::string_view> fields = first_line_fields(stat.substr(close + 1));
  if (fields.size() < 7) return std::nullopt;
  const std::optional<double> flags = counter(fields[6]);
  if (!flags || *flags >= 1.8e19) return std::nullopt;
  constexpr unsigned long long kPfKthread = 0x00200000;
  return (static_cast<unsigned long long>(*flags) & kPfKthread) != 0;
}

MachineThreads read_machine_threads() {
  MachineThreads all;
  std::error_code ec;
  for (std::filesystem::directory_iterator p("/proc", ec), end; !ec && p != end; p.increment(ec)) {
    const std::optional<double> pid = text::to_number(p->path().filename().string());
    if (!pid) continue;
    ProcessThreads proc;
    std::string name = text::read_file_or_empty((p->path() / "comm").c_str());
    while (!name.empty() && (name.back() == '\n' || name.back() == ' ')) name.pop_back();
    proc.name = name;
    proc.kernel = parse_kernel_thread(text::read_file_or_empty((p->path() / "stat").c_str())).value_or(false);
    std::error_code tec;
    for (std::filesystem::directory_iterator t(p->path() / "task", tec); !tec && t != end; t.increment(tec)) {
      const std::optional<double> tid = text::to_number(t->path().filename().string());
      if (!tid) continue;
      if (const std::optional<ThreadTime> times = parse_schedstat(text::read_file_or_empty((t->path() / "schedstat").c_str())))
        proc.threads[static_cast<long>(*tid)] = *times;
    }
    if (!proc.threads.empty()) all[static_cast<long>(*pid)] = std::move(proc);  // (a process that ended since the listing: left out)
  }
  return all;
}

namespace {

// A thread's times at an earlier reading (zero where it was not there: born between the two)
ThreadTime earlier(const MachineThreads& before, long pid, long tid) {
  const auto proc = before.find(pid);
  if (proc == before.end()) return {};
  const auto it = proc->second.threads.find(tid);
  return it == proc->second.threads.end() ? ThreadTime{} : it->second;
}

}  // namespace

std::vector<BusyProcess> busiest_others(const MachineThreads& before, const MachineThreads& after, long self_pid, size_t most) {
  std::vector<BusyProcess> out;
  for (const auto& [pid, proc] : after) {
    if (pid == self_pid) continue;
    BusyProcess b{pid, proc.name, proc.kernel, 0, 0};
    for (const auto& [tid, t] : proc.threads) {
      const ThreadTime from = earlier(before, pid, tid);
      b.cpu_ms += std::max(0.0, t.run_ns - from.run_ns) / 1e6;
      b.slices += std::max(0.0, t.slices - from.slices);
    }
    if (b.cpu_ms > 0) out.push_back(std::move(b));
  }
  std::sort(out.begin(), out.end(),
            [](const BusyProcess& a, const BusyProcess& b) { return a.cpu_ms != b.cpu_ms ? a.cpu_ms > b.cpu_ms : a.pid < b.pid; });
  if (out.size() > most) out.resize(most);
  return out;
}

std::vector<WatchedThread> threads_to_watch(const MachineThreads& before, const MachineThreads& after, long self_pid, size_t most) {
  std::vector<std::pair<double, WatchedThread>> ran;
  for (const auto& [pid, proc] : after) {
    if (pid == self_pid) continue;
    for (const auto& [tid, t] : proc.threads) {
      const double ns = t.run_ns - earlier(before, pid, tid).run_ns;
      if (ns > 0)
        ran.push_back(
            {ns, {pid, tid, proc.name, proc.kernel, "/proc/" + std::to_string(pid) + "/task/" + std::to_string(tid) + "/schedstat"}});
    }
  }
  std::sort(ran.begin(), ran.end(),
            [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second.tid < b.second.tid; });
  std::vector<WatchedThread> out;
  for (size_t k = 0; k < ran.size() && k < most; ++k) out.push_back(ran[k].second);
  return out;
}

ThreadTimes read_watched(const std::vector<WatchedThread>& watch) {
  ThreadTimes times;
  for (const WatchedThread& w : watch)
    if (const std::optional<ThreadTime> t = parse_schedstat(text::read_file_or_empty(w.schedstat.c_str()))) times[w.tid] = *t;
  return times;
}

std::pair<std::string, double> busiest_watched(const std::vector<WatchedThread>& watch, const ThreadTimes& before,
                                               const ThreadTimes& after) {
  std::map<long, std::pair<std::string, double>> by_pid;  // (in pid order: a tie goes to the lower)
  for (const WatchedThread& w : watch) {
    const auto a = before.find(w.tid), b = after.find(w.tid);
    if (a == before.end() || b == after.end()) continue;
    auto& [name, ms] = by_pid[w.pid];
    name = w.name;
    ms += std::max(0.0, b->second.run_ns - a->second.run_ns) / 1e6;
  }
  std::pair<std::string, double> best{"", 0.0};
  for (const auto& [pid, process] : by_pid)
    if (process.second > best.second) best = process;
  return best;
}

long current_process_id() {
#ifdef __linux__
  return static_cast<long>(::getpid());
#else
  return -1;
#endif
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
