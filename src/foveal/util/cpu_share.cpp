// foveal/util/cpu_share.cpp — the kernel's CPU counters around a timed run.
#include "foveal/util/cpu_share.h"

#include <algorithm>
#include <charconv>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace foveal {

namespace {

// The whitespace-separated fields of a line, as numbers (false at the first that is not one).
bool numbers(std::string_view text, std::vector<double>& out) {
  out.clear();
  size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i >= text.size() || text[i] == '\n') break;
    size_t j = i;
    while (j < text.size() && text[j] != ' ' && text[j] != '\t' && text[j] != '\n') ++j;
    unsigned long long v = 0;
    const auto [end, ec] = std::from_chars(text.data() + i, text.data() + j, v);
    if (ec != std::errc() || end != text.data() + j) return false;
    out.push_back(static_cast<double>(v));
    i = j;
  }
  return true;
}

std::string read_all(const char* path) {
  std::ifstream in(path);
  if (!in) return {};
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

CpuTimes parse_cpu_times(std::string_view proc_stat, std::string_view self_stat) {
  CpuTimes t;
  // /proc/stat's first line: "cpu  user nice system idle iowait irq softirq steal guest guest_nice"
  // (guest time is counted in user already)
  if (proc_stat.substr(0, 4) != "cpu ") return t;
  const size_t eol = proc_stat.find('\n');
  std::vector<double> f;
  if (!numbers(proc_stat.substr(4, eol == std::string_view::npos ? std::string_view::npos : eol - 4), f) || f.size() < 8) return t;
  const double user = f[0], nice = f[1], system = f[2], idle = f[3], iowait = f[4], irq = f[5], softirq = f[6], steal = f[7];
  // /proc/self/stat: "pid (comm) state ppid …", utime and stime the 14th and 15th fields; the
  // command may hold spaces and parentheses, so fields are counted from its last ')'
  const size_t close = self_stat.rfind(')');
  if (close == std::string_view::npos) return t;
  std::vector<std::string_view> fields;
  for (size_t i = close + 1; i < self_stat.size();) {
    while (i < self_stat.size() && (self_stat[i] == ' ' || self_stat[i] == '\n')) ++i;
    size_t j = i;
    while (j < self_stat.size() && self_stat[j] != ' ' && self_stat[j] != '\n') ++j;
    if (j > i) fields.push_back(self_stat.substr(i, j - i));
    i = j;
  }
  if (fields.size() < 13) return t;  // state is field 3: utime and stime are the 12th and 13th after ')'
  std::vector<double> self;
  std::string both(fields[11]);
  both += ' ';
  both += fields[12];
  if (!numbers(both, self) || self.size() != 2) return t;
  t.total = user + nice + system + idle + iowait + irq + softirq + steal;
  t.busy = user + nice + system + irq + softirq;
  t.steal = steal;
  t.self = self[0] + self[1];
  t.known = true;
  return t;
}

CpuTimes read_cpu_times() { return parse_cpu_times(read_all("/proc/stat"), read_all("/proc/self/stat")); }

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
