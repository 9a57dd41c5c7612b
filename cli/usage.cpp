#include <scan2lod/cli/usage.h>

#include <scan2lod/cli/terminal.h>

#include <algorithm>
#include <cstring>
#include <regex>
#include <thread>
#include <vector>

namespace scan2lod::cli {
namespace {

// Edits (insertions, deletions, substitutions, swaps of neighbours) from a to b.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i)
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1])});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

std::vector<const CLI::App*> commands_of(const CLI::App& app) {
  return app.get_subcommands([](const CLI::App*) { return true; });
}

std::string command_list(const CLI::App& app) {
  std::string names;
  for (const CLI::App* c : commands_of(app)) names += (names.empty() ? "" : ", ") + c->get_name();
  return names;
}

// "Could not convert: --percent = abc" -> "--percent: expected a number, got 'abc'".
std::string conversion_message(const CLI::App* app, const std::string& what) {
  static const std::regex pattern(R"(^Could not convert: (\S+) = (.*)$)");
  std::smatch m;
  if (!std::regex_match(what, m, pattern)) return what;
  const std::string name = m[1], value = m[2];
  std::string type;
  for (const CLI::App* c : app->get_subcommands())
    if (const CLI::Option* o = c->get_option_no_throw(name)) type = o->get_type_name();
  std::string expected = "a value it can read";
  if (type.rfind("FLOAT", 0) == 0) expected = "a number";
  else if (type.rfind("INT", 0) == 0 || type.rfind("UINT", 0) == 0) expected = "a whole number";
  return name + ": expected " + expected + ", got '" + value + "'";
}

}  // namespace

std::string usage_failure_message(const CLI::App* app, const CLI::Error& e) {
  std::string what = e.what();
  if (what == "A subcommand is required") what = "no command given; expected one of " + command_list(*app);
  else if (e.get_name() == "ConversionError") what = conversion_message(app, what);
  // The command whose --help explains the flags, when parsing reached one.
  const auto parsed = app->get_subcommands();
  const std::string help = parsed.empty() ? "scan2lod --help" : "scan2lod " + parsed.back()->get_name() + " --help";
  return "scan2lod: error: " + what + "\nRun '" + help + "' for more information.\n";
}

std::string unknown_command_message(const CLI::App& app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "-h" || word == "--help" || word == "--help-all" || word == "--version") return "";
    if (word.empty() || word[0] == '-') continue;  // scan2lod's own flags take no values
    const std::vector<const CLI::App*> commands = commands_of(app);
    for (const CLI::App* c : commands)
      if (c->check_name(word)) return "";
    std::string nearest;
    std::size_t best = 3;  // more edits than this is another word, not a typo
    for (const CLI::App* c : commands) {
      const std::size_t d = edit_distance(word, c->get_name());
      if (d < best && d < c->get_name().size() / 2 + 1) best = d, nearest = c->get_name();
    }
    return "unknown command '" + word + "'" + (nearest.empty() ? "; the commands are " + command_list(app)
                                                                : "; did you mean '" + nearest + "'?");
  }
  return "";
}

CLI::Option* add_threads_option(CLI::App* cmd, int* threads) {
  return cmd
      ->add_option("-j,--threads", *threads,
                   "Threads (0: all cores; a count above the machine's cores is lowered to them, with a warning)")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& text) {
            return !text.empty() && text[0] == '-' ? "expected 0 (all cores) or a positive count, got " + text
                                                   : std::string();
          },
          "", ""));
}

int usable_threads(int threads) {
  const int cores = int(std::max(1u, std::thread::hardware_concurrency()));
  if (threads <= cores) return threads;
  warn("--threads " + std::to_string(threads) + " is more than this machine's " + std::to_string(cores) +
       " cores; using " + std::to_string(cores));
  return cores;
}

}  // namespace scan2lod::cli
