// A small stand-in for libFuzzer's main() where clang is absent, with libFuzzer's flags:
//   TARGET [-max_total_time=S] [-runs=N] [-timeout=S] [-rss_limit_mb=M] [-artifact_prefix=P] DIR_OR_FILE...
// Without -max_total_time and -runs it replays every file once (the regression corpus under ctest).
// Otherwise it mutates the given inputs at random (no coverage feedback: bit flips, interesting bytes and
// integers, numbers in text replaced by boundary values, chunks cut, copied and spliced) until the time or
// run budget is spent. As libFuzzer, it stops at the first finding and keeps the input as
// P{crash,timeout,oom}-<hash>: a signal, a run over -timeout seconds (SIGALRM), or memory beyond
// -rss_limit_mb (address-space limit, seen as std::bad_alloc).
#include <fcntl.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <new>
#include <random>
#include <string>
#include <unistd.h>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
// Defined only when ASan is linked in (tested at run time: the build may undefine __SANITIZE_ADDRESS__).
extern "C" void __asan_init() __attribute__((weak));

namespace {

namespace fs = std::filesystem;

struct Flags {
  double max_total_time = 0;
  long runs = 0;
  unsigned timeout = 20;
  long rss_limit_mb = 2048;
  std::string artifact_prefix = "./";
  std::vector<std::string> inputs;
};

// The input being run and where a finding goes, for the signal handlers (which may only write(2)).
std::vector<std::uint8_t> g_current;
char g_artifact[4096];

void save_finding(const char* kind) {
  std::uint64_t hash = 14695981039346656037ull;
  for (std::uint8_t b : g_current) hash = (hash ^ b) * 1099511628211ull;
  char path[4200];
  std::snprintf(path, sizeof path, "%s%s-%016llx", g_artifact, kind, static_cast<unsigned long long>(hash));
  const int fd = ::open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0) {
    if (!g_current.empty() && ::write(fd, g_current.data(), g_current.size()) < 0) {}
    ::close(fd);
  }
  const char* lead = "\n==mutation_driver== finding saved as ";
  if (::write(2, lead, std::strlen(lead)) < 0 || ::write(2, path, std::strlen(path)) < 0 || ::write(2, "\n", 1) < 0) {}
}

extern "C" void on_crash(int signal) {
  save_finding(signal == SIGALRM ? "timeout" : "crash");
  ::_exit(signal == SIGALRM ? 70 : 77);
}

void on_terminate() {
  bool out_of_memory = false;
  try {
    if (auto e = std::current_exception()) std::rethrow_exception(e);
  } catch (const std::bad_alloc&) {
    out_of_memory = true;
  } catch (...) {
  }
  save_finding(out_of_memory ? "oom" : "crash");
  ::_exit(out_of_memory ? 71 : 77);
}

void install_handlers(const Flags& flags) {
  std::snprintf(g_artifact, sizeof g_artifact, "%s", flags.artifact_prefix.c_str());
  for (int s : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGALRM}) std::signal(s, on_crash);
  std::set_terminate(on_terminate);
  if (__asan_init) return;  // ASan reserves terabytes of address space for its shadow: no limit under it
  const rlimit limit{static_cast<rlim_t>(flags.rss_limit_mb) << 20, static_cast<rlim_t>(flags.rss_limit_mb) << 20};
  setrlimit(RLIMIT_AS, &limit);
}

Flags parse_flags(int argc, char** argv) {
  Flags f;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&](const char* name) { return a.substr(std::strlen(name)); };
    if (a.rfind("-max_total_time=", 0) == 0) f.max_total_time = std::stod(value("-max_total_time="));
    else if (a.rfind("-runs=", 0) == 0) f.runs = std::stol(value("-runs="));
    else if (a.rfind("-timeout=", 0) == 0) f.timeout = static_cast<unsigned>(std::stoul(value("-timeout=")));
    else if (a.rfind("-rss_limit_mb=", 0) == 0) f.rss_limit_mb = std::stol(value("-rss_limit_mb="));
    else if (a.rfind("-artifact_prefix=", 0) == 0) f.artifact_prefix = value("-artifact_prefix=");
    else if (a.rfind("-", 0) == 0) std::fprintf(stderr, "mutation_driver: ignoring %s\n", a.c_str());
    else f.inputs.push_back(a);
  }
  return f;
}

std::vector<std::vector<std::uint8_t>> load_inputs(const std::vector<std::string>& names) {
  std::vector<fs::path> files;
  for (const std::string& name : names) {
    if (!fs::is_directory(name)) files.emplace_back(name);
    else
      for (const auto& entry : fs::directory_iterator(name))
        if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<std::vector<std::uint8_t>> inputs;
  for (const fs::path& file : files) {
    std::ifstream in(file, std::ios::binary);
    inputs.emplace_back(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return inputs;
}

void run_one(const std::vector<std::uint8_t>& input, unsigned timeout) {
  g_current = input;
  ::alarm(timeout);
  LLVMFuzzerTestOneInput(g_current.data(), g_current.size());
  ::alarm(0);
}

// Numbers in text replaced by these reach the header and size checks' edges.
const char* const kNumbers[] = {"0", "1", "-1", "2", "3", "8", "65535", "65536", "2147483647", "2147483648",
                                "4294967295", "4294967296", "18446744073709551615", "99999999999999999999",
                                "1e308", "-1e308", "nan", "inf", "0.0", "-0"};
const std::uint32_t kWords[] = {0, 1, 0x7f, 0xff, 0x7fff, 0xffff, 0x7fffffff, 0x80000000, 0xffffffff, 0x10000};

class Mutator {
public:
  explicit Mutator(const std::vector<std::vector<std::uint8_t>>& seeds) : seeds_(seeds), random_(20261201) {}

  std::vector<std::uint8_t> next() {
    std::vector<std::uint8_t> data = seeds_[pick(seeds_.size())];
    for (std::size_t n = 1 + pick(4); n > 0; --n) mutate(data);
    return data;
  }

private:
  std::size_t pick(std::size_t n) { return n == 0 ? 0 : std::uniform_int_distribution<std::size_t>(0, n - 1)(random_); }

  void mutate(std::vector<std::uint8_t>& d) {
    const std::size_t at = pick(d.size() + 1);
    switch (pick(8)) {
      case 0: if (!d.empty()) d[std::min(at, d.size() - 1)] ^= static_cast<std::uint8_t>(1u << pick(8)); break;
      case 1: if (!d.empty()) d[std::min(at, d.size() - 1)] = static_cast<std::uint8_t>(kWords[pick(10)]); break;
      case 2: {  // a little-endian integer over 4 bytes (binary size fields)
        const std::uint32_t w = kWords[pick(10)];
        for (std::size_t i = 0; i < 4 && at + i < d.size(); ++i) d[at + i] = static_cast<std::uint8_t>(w >> (8 * i));
        break;
      }
      case 3: replace_number(d, at); break;
      case 4: d.erase(d.begin() + static_cast<std::ptrdiff_t>(at), d.begin() + static_cast<std::ptrdiff_t>(std::min(d.size(), at + 1 + pick(64)))); break;
      case 5: {  // copy a chunk of itself elsewhere
        const std::size_t from = pick(d.size() + 1), length = std::min(d.size() - from, 1 + pick(64));
        const std::vector<std::uint8_t> chunk(d.begin() + static_cast<std::ptrdiff_t>(from), d.begin() + static_cast<std::ptrdiff_t>(from + length));
        d.insert(d.begin() + static_cast<std::ptrdiff_t>(std::min(at, d.size())), chunk.begin(), chunk.end());
        break;
      }
      case 6: d.resize(at); break;
      default: {  // splice: our head, another seed's tail
        const auto& other = seeds_[pick(seeds_.size())];
        const std::size_t from = pick(other.size() + 1);
        d.resize(at);
        d.insert(d.end(), other.begin() + static_cast<std::ptrdiff_t>(from), other.end());
      }
    }
  }

  // The run of digits at or after `at` becomes a boundary value.
  void replace_number(std::vector<std::uint8_t>& d, std::size_t at) {
    auto digit = [&](std::size_t i) { return i < d.size() && d[i] >= '0' && d[i] <= '9'; };
    while (at < d.size() && !digit(at)) ++at;
    if (at >= d.size()) return;
    std::size_t end = at;
    while (digit(end)) ++end;
    const std::string number = kNumbers[pick(std::size(kNumbers))];
    d.erase(d.begin() + static_cast<std::ptrdiff_t>(at), d.begin() + static_cast<std::ptrdiff_t>(end));
    d.insert(d.begin() + static_cast<std::ptrdiff_t>(at), number.begin(), number.end());
  }

  const std::vector<std::vector<std::uint8_t>>& seeds_;
  std::mt19937_64 random_;
};

}  // namespace

int main(int argc, char** argv) {
  const Flags flags = parse_flags(argc, argv);
  install_handlers(flags);
  const std::vector<std::vector<std::uint8_t>> inputs = load_inputs(flags.inputs);
  if (flags.max_total_time <= 0 && flags.runs <= 0) {
    for (const auto& input : inputs) run_one(input, flags.timeout);
    std::printf("mutation_driver: replayed %zu inputs, no finding\n", inputs.size());
    return 0;
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "mutation_driver: no seed inputs given\n");
    return 1;
  }
  Mutator mutator(inputs);
  const auto start = std::chrono::steady_clock::now();
  long runs = 0;
  double elapsed = 0;
  for (; (flags.runs <= 0 || runs < flags.runs) && (flags.max_total_time <= 0 || elapsed < flags.max_total_time); ++runs) {
    run_one(mutator.next(), flags.timeout);
    elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  std::printf("mutation_driver: %ld runs in %.1f s (%.0f/s) from %zu seeds, no finding\n", runs, elapsed,
              static_cast<double>(runs) / std::max(elapsed, 1e-9), inputs.size());
  return 0;
}
