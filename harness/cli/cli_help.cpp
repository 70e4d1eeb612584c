#include "harness/cli/cli_help.hpp"

#include <algorithm>
#include <utility>

namespace ricochet {
namespace {

bool is_help(const CLI::App& app, const CLI::Option* o) { return o == app.get_help_ptr(); }

bool takes_value(const CLI::Option* o) { return o->get_expected_max() > 0; }  // not a flag

std::vector<const CLI::App*> commands(const CLI::App& root) {
  return root.get_subcommands([](const CLI::App* a) { return !a->get_group().empty(); });
}

// "--out DIR", "-q, --quiet", "CASE.toml".
std::string label(const CLI::Option* o) {
  if (o->get_positional()) return o->get_name(true, false);
  std::string s;
  for (const auto& n : o->get_snames()) s += (s.empty() ? "-" : ", -") + n;
  for (const auto& n : o->get_lnames()) s += (s.empty() ? "--" : ", --") + n;
  return takes_value(o) ? s + " " + o->get_type_name() : s;
}

// The description, one line per argument, the footer (exit statuses).
std::string section(const CLI::App& app) {
  std::vector<std::pair<std::string, std::string>> rows;
  if (const Script* script = script_of(app)) {
    for (const ScriptArg& a : script->args) rows.emplace_back(a.names + (a.value.empty() ? "" : " " + a.value), a.help);
  } else {
    for (const CLI::Option* o : ordered_options(app)) rows.emplace_back(label(o), o->get_description());
  }
  std::size_t width = 0;
  for (const auto& r : rows) width = std::max(width, r.first.size());
  std::string s = app.get_description() + "\n";
  for (const auto& [l, h] : rows) s += "  " + l + std::string(width + 2 - l.size(), ' ') + h + "\n";
  if (!app.get_footer().empty()) s += "  " + app.get_footer() + "\n";
  return s;
}

class Help : public CLI::Formatter {
 public:
  std::string make_help(const CLI::App* app, std::string, CLI::AppFormatMode) const override {
    if (app->get_parent() == nullptr) return complete_usage(*app);
    return "usage: " + synopsis(*app) + "\n" + section(*app);
  }
};

}  // namespace

const std::vector<Script>& scripts() {
  static const std::vector<Script> s = {
      {"report", "make_report.py",
       "the HTML report of a folder (docs/report.md): of a study's output folder (study.json) its "
       "page, STUDY/report/index.html; of a folder of them each study's page and OUT/index.html; "
       "of any other sweep folder its default page, DIR/report/index.html; runs "
       "reports/make_report.py with the arguments as given",
       "exit status: 0 written, 2 bad input (a layout error names the study.toml and the key), 1 other error",
       {{"DIR", "", "a study's output folder, a folder of them (ricochet reproduce --out), or a finished sweep folder"},
        {"--study", "STUDY_OUT", "a study's output folder: its page (what DIR does for a folder with study.json)"},
        {"--index", "OUT", "OUT/index.html only: one row per OUT/<study>/study.json"},
        {"--out", "OUT", "report folder (default DIR/report; not with --index or a folder of studies)"},
        {"--max-run-plots", "N", "plug-ins that draw run histories draw at most N (default 30)"},
        {"-h, --help", "", "the script's help"}}},
      {"plot", "plot_run.py",
       "one PNG of a run's history (docs/report.md): RUN_DIR/history.png; runs reports/plot_run.py "
       "with the arguments as given",
       "exit status: 0 written, 2 bad input, 1 other error",
       {{"RUN_DIR", "", "a run's output folder (history.csv)"},
        {"--out", "PNG", "output PNG (default RUN_DIR/history.png)"},
        {"-h, --help", "", "the script's help"}}},
  };
  return s;
}

const Script* script_of(const CLI::App& app) {
  for (const Script& s : scripts())
    if (s.command == app.get_name()) return &s;
  return nullptr;
}

std::vector<const CLI::Option*> ordered_options(const CLI::App& app) {
  std::vector<const CLI::Option*> out;
  for (const CLI::Option* o : app.get_options([](const CLI::Option* o) { return o->get_positional(); })) out.push_back(o);
  for (const CLI::Option* o : app.get_options([](const CLI::Option* o) { return o->nonpositional(); }))
    if (!is_help(app, o)) out.push_back(o);
  if (const CLI::Option* h = app.get_help_ptr()) out.push_back(h);
  return out;
}

std::string long_name(const CLI::Option* o) {
  return o->get_lnames().empty() ? "-" + o->get_snames().front() : "--" + o->get_lnames().front();
}

std::string synopsis(const CLI::App& app) {
  std::string s = "ricochet " + app.get_name();
  if (const Script* script = script_of(app)) {
    for (const ScriptArg& a : script->args) {
      if (a.names[0] != '-') s += " " + a.names;
      else if (a.names != "-h, --help") s += " [" + a.names + (a.value.empty() ? "" : " " + a.value) + "]";
    }
    return s;
  }
  for (const CLI::Option* o : ordered_options(app)) {
    if (is_help(app, o)) continue;
    if (o->get_positional()) {
      // One that takes any number of words (`reproduce [STUDY...]`) may be left out.
      s += o->get_expected_max() > 1 ? " [" + o->get_name(true, false) + "...]" : " " + o->get_name(true, false);
      continue;
    }
    s += " [" + long_name(o) + (takes_value(o) ? " " + o->get_type_name() : "") + "]";
    if (o->get_multi_option_policy() == CLI::MultiOptionPolicy::TakeAll) s += "...";
  }
  return s;
}

std::string complete_usage(const CLI::App& root) {
  std::string s = root.get_description() + "\n\n";
  std::string lead = "usage: ";
  for (const CLI::App* c : commands(root)) {
    s += lead + synopsis(*c) + "\n";
    lead = "       ";
  }
  s += lead + "ricochet --version | --help\n";
  s += lead + "ricochet COMMAND --help\n\n";
  s += "  --version   print the version and exit\n";
  s += "  -h, --help  this text; after a command, that command's options\n";
  for (const CLI::App* c : commands(root)) s += "\n" + c->get_name() + ": " + section(*c);
  return s;
}

std::shared_ptr<CLI::Formatter> help_formatter() { return std::make_shared<Help>(); }

}  // namespace ricochet
