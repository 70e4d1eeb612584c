// Gates (harness/gates/gates.hpp) on hand-written sweep tables, and the CSV reader they use.
// Every gate kind is shown to pass and to fail: a gate that cannot fail is a defect.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "harness/outputs/csv_reader.hpp"
#include "harness/gates/gates.hpp"
#include "harness/cli/cli.hpp"
#include "harness/input/input_error.hpp"
#include "tests/support/temp_dir.hpp"

namespace ricochet {
namespace {

namespace fs = std::filesystem;

// A summary.csv as `ricochet sweep` writes it: run columns, swept keys, then the flattened
// summary.json keys (which repeat `status`; the first column of a name wins).
const char* const kSweep =
    "run_id,group,status,reason,mesh,time.dt,scheme,energy_error_max,penetration_max,"
    "von_mises_max,wall_seconds,status,diverged.reason\n"
    "r1,table1,diverged,\"energy growth, step 2\",M1,1e-04,semi_explicit,,,,0.01,diverged,energy growth\n"
    "r2,table1,ok,,M1,1e-05,semi_explicit,0.0078,2.7e-20,785800,0.036,ok,\n"
    "r3,table1,ok,,M1,0.000001,semi_explicit,0.0078,2.5e-22,788800,0.12,ok,\n"
    "r4,table1,ok,,M2,1e-06,semi_explicit,0.0025,8.5e-22,847900,1.06,ok,\n"
    "r5,table1,ok,,M2,1e-06,implicit,0.001,1e-12,953800,12.5,ok,\n"
    "r6,table1,failed,\"exit 1: \"\"cannot write\"\"\",M2,1e-05,implicit,,,,,,\n";

class TempDir {
 public:
  TempDir() {
    path_ = ricochet::test_support::fresh_test_dir("ricochet_gates_");
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }
  fs::path write(const std::string& name, const std::string& content) const {
    const fs::path p = path_ / name;
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }

 private:
  fs::path path_;
};

CsvTable sweep() { return parse_csv(kSweep, "sweep/summary.csv"); }

GateFile gates(const std::string& toml) { return parse_gates(toml, "gates.toml"); }

GateResult one(const CsvTable& t, const std::string& toml) {
  const auto results = evaluate_gates(t, gates(toml));
  EXPECT_EQ(results.size(), 1u);
  return results.at(0);
}

std::string all_failures(const GateResult& r) {
  std::string s;
  for (const auto& f : r.failures) s += f + "\n";
  return s;
}

// Expects parse_gates to throw an InputError whose message contains every piece.
void expect_rejected(const std::string& toml, const std::vector<std::string>& pieces) {
  try {
    parse_gates(toml, "ci/gates/bad.toml");
    ADD_FAILURE() << "accepted:\n" << toml;
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    for (const auto& p : pieces) EXPECT_NE(m.find(p), std::string::npos) << "'" << p << "' not in: " << m;
  }
}

void expect_csv_error(const std::string& text, const std::string& piece) {
  try {
    parse_csv(text, "t.csv");
    ADD_FAILURE() << "accepted: " << text;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(piece), std::string::npos) << e.what();
  }
}

// ----------------------------------------------------------------------------------------------
// A minimal XML reader: enough to prove the JUnit output well formed (balanced tags, quoted
// attributes, only the five entities and character references) and to look inside it.
struct XmlElement {
  std::string name;
  std::map<std::string, std::string> attrs;
  std::vector<XmlElement> children;
  std::string text;
};

class XmlReader {
 public:
  explicit XmlReader(std::string s) : s_(std::move(s)) {}
  XmlElement document() {
    if (s_.rfind("<?xml", 0) == 0) {
      const auto e = s_.find("?>");
      if (e == std::string::npos) throw std::runtime_error("unterminated declaration");
      i_ = e + 2;
    }
    skip_space();
    XmlElement root = element();
    skip_space();
    if (i_ != s_.size()) throw std::runtime_error("content after the root element");
    return root;
  }

 private:
  void skip_space() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  void expect(char c) {
    if (i_ >= s_.size() || s_[i_] != c) throw std::runtime_error(std::string("expected '") + c + "' at " + std::to_string(i_));
    ++i_;
  }
  std::string name() {
    const std::size_t b = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '-' || s_[i_] == '_' || s_[i_] == ':')) ++i_;
    if (i_ == b) throw std::runtime_error("expected a name at " + std::to_string(i_));
    return s_.substr(b, i_ - b);
  }
  std::string chars(char stop) {  // text or attribute value up to `stop`, entities decoded
    std::string out;
    while (i_ < s_.size() && s_[i_] != stop) {
      const char c = s_[i_];
      if (c == '<' && stop == '"') throw std::runtime_error("'<' in an attribute value");
      if (static_cast<unsigned char>(c) < 0x20 && c != '\n' && c != '\t' && c != '\r')
        throw std::runtime_error("control character");
      if (c == '&') {
        const auto semi = s_.find(';', i_);
        if (semi == std::string::npos) throw std::runtime_error("unterminated entity");
        const std::string ent = s_.substr(i_ + 1, semi - i_ - 1);
        static const std::map<std::string, char> known = {{"amp", '&'}, {"lt", '<'}, {"gt", '>'}, {"quot", '"'}, {"apos", '\''}};
        if (known.count(ent)) out += known.at(ent);
        else if (ent.size() > 1 && ent[0] == '#' && ent.find_first_not_of("0123456789", 1) == std::string::npos)
          out += static_cast<char>(std::stoi(ent.substr(1)));
        else throw std::runtime_error("unknown entity &" + ent + ";");
        i_ = semi + 1;
        continue;
      }
      out += c;
      ++i_;
    }
    return out;
  }
  XmlElement element() {
    expect('<');
    XmlElement e;
    e.name = name();
    while (true) {
      skip_space();
      if (i_ < s_.size() && s_[i_] == '/') {
        ++i_;
        expect('>');
        return e;
      }
      if (i_ < s_.size() && s_[i_] == '>') {
        ++i_;
        break;
      }
      const std::string a = name();
      expect('=');
      expect('"');
      const std::string v = chars('"');
      expect('"');
      if (!e.attrs.emplace(a, v).second) throw std::runtime_error("duplicate attribute " + a);
    }
    while (true) {
      e.text += chars('<');
      if (i_ >= s_.size()) throw std::runtime_error("unclosed <" + e.name + ">");
      if (s_.compare(i_, 2, "</") == 0) {
        i_ += 2;
        if (name() != e.name) throw std::runtime_error("mismatched end tag for <" + e.name + ">");
        skip_space();
        expect('>');
        return e;
      }
      e.children.push_back(element());
    }
  }
  std::string s_;
  std::size_t i_ = 0;
};

// ----------------------------------------------------------------------------------------------
// CSV reader

TEST(CsvReader, ReadsQuotedFieldsEscapedQuotesAndLineBreaks) {
  const CsvTable t = parse_csv(
      "\xEF\xBB\xBF" "a,b,c\r\n"
      "1,\"x, y\",\"say \"\"hi\"\"\"\r\n"
      "\"two\nlines\",,\"\"\r\n"
      "\r\n"
      "3,\"\",last",
      "t.csv");
  ASSERT_EQ(t.columns, (std::vector<std::string>{"a", "b", "c"}));
  ASSERT_EQ(t.rows.size(), 3u);
  EXPECT_EQ(t.rows[0], (std::vector<std::string>{"1", "x, y", "say \"hi\""}));
  EXPECT_EQ(t.rows[1], (std::vector<std::string>{"two\nlines", "", ""}));
  EXPECT_EQ(t.rows[2], (std::vector<std::string>{"3", "", "last"}));
  EXPECT_EQ(t.lines, (std::vector<long>{2, 3, 6}));  // the quoted line break counts; the blank line is skipped
  EXPECT_EQ(*t.find(0, "b"), "x, y");
  EXPECT_EQ(t.find(0, "nope"), nullptr);
  EXPECT_EQ(t.at(2, "c"), "last");
  EXPECT_THROW(t.at(0, "nope"), InputError);
}

TEST(CsvReader, RepeatedColumnNameFirstWins) {
  const CsvTable t = sweep();
  EXPECT_EQ(t.columns.size(), 13u);
  EXPECT_EQ(*t.column_index("status"), 2u);
  EXPECT_EQ(*t.find(5, "status"), "failed");
  EXPECT_EQ(*t.find(5, "reason"), "exit 1: \"cannot write\"");
  EXPECT_EQ(*t.find(0, "reason"), "energy growth, step 2");
}

TEST(CsvReader, ErrorsNameFileAndLine) {
  expect_csv_error("a,b\n1,2\n3\n", "t.csv:3: row has 1 fields; the header has 2 columns");
  expect_csv_error("a,b\n1,2\n\"3,4\n5,6\n", "t.csv:3: unterminated quoted field 1 (column 'a')");
  expect_csv_error("a,b\n1,x\"y\n", "t.csv:2: '\"' inside unquoted field 2 (column 'b')");
  expect_csv_error("a,b\n\"1\"x,2\n", "t.csv:2: text after the closing quote of field 1");
  expect_csv_error("a,,c\n", "t.csv:1: header: column 2 has an empty name");
  expect_csv_error("", "t.csv: empty file");
  expect_csv_error("\n\n", "t.csv: empty file");
  try {
    read_csv("/nonexistent/ricochet/summary.csv");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/ricochet/summary.csv: cannot read"), std::string::npos) << e.what();
  }
}

TEST(CsvReader, ReadsFiles) {
  TempDir dir;
  const CsvTable t = read_csv(dir.write("s.csv", kSweep));
  EXPECT_EQ(t.rows.size(), 6u);
  EXPECT_EQ(t.file, (dir.path() / "s.csv").string());
}

TEST(CsvReader, Numbers) {
  EXPECT_EQ(parse_csv_number("1e-06"), 1e-6);
  EXPECT_EQ(parse_csv_number("0.000001"), 1e-6);
  EXPECT_EQ(parse_csv_number("1E-6"), 1e-6);
  EXPECT_EQ(parse_csv_number(" +2.5 "), 2.5);
  EXPECT_EQ(parse_csv_number("-3"), -3.0);
  EXPECT_TRUE(std::isinf(*parse_csv_number("inf")));
  EXPECT_TRUE(std::isinf(*parse_csv_number("1e999")));
  EXPECT_TRUE(std::isnan(*parse_csv_number("nan")));
  for (const char* bad : {"", " ", "M1", "1e", "1.0x", "0x10", "+-1", "1,5"})
    EXPECT_FALSE(parse_csv_number(bad).has_value()) << bad;
}

// ----------------------------------------------------------------------------------------------
// max / min

TEST(Gates, MaxPassesAndReportsTheClosestRow) {
  const auto r = one(sweep(), R"(
    [[gate]]
    name = "energy bound on stable runs"
    kind = "max"
    column = "energy_error_max"
    limit = 0.02
    strict = true
    where = { status = "ok" }
  )");
  EXPECT_TRUE(r.passed) << all_failures(r);
  EXPECT_EQ(r.checked_rows, 4);
  EXPECT_EQ(r.name, "energy bound on stable runs");
  EXPECT_EQ(describe(r).rfind("PASS energy bound on stable runs (4 rows)", 0), 0u) << describe(r);
  ASSERT_EQ(r.notes.size(), 1u);
  EXPECT_NE(r.notes[0].find("run r2: energy_error_max = 0.0078 < 0.02 (margin 0.0122, 61 %)"), std::string::npos)
      << r.notes[0];
}

TEST(Gates, MaxFailsNamingGateRunAndMargin) {
  std::string csv = kSweep;
  csv.replace(csv.find("0.0025"), 6, "0.0312");
  const auto r = one(parse_csv(csv, "s.csv"), R"(
    [[gate]]
    name = "energy bound"
    kind = "max"
    column = "energy_error_max"
    limit = 0.02
    where = { status = "ok" }
  )");
  EXPECT_FALSE(r.passed);
  ASSERT_EQ(r.failures.size(), 1u);
  EXPECT_EQ(r.failures[0], "run r4: energy_error_max = 0.0312 > 0.02 (by 0.0112, 56 %)");
  const std::string line = describe(r);
  EXPECT_EQ(line, "FAIL energy bound: run r4: energy_error_max = 0.0312 > 0.02 (by 0.0112, 56 %)");
}

TEST(Gates, StrictLimitFailsOnEquality) {
  const std::string toml = R"(
    [[gate]]
    name = "strict"
    kind = "max"
    column = "energy_error_max"
    limit = 0.0078
    where = { run_id = "r2" }
  )";
  EXPECT_TRUE(one(sweep(), toml).passed);
  const auto r = one(sweep(), toml + "strict = true\n");
  EXPECT_FALSE(r.passed);
  EXPECT_NE(all_failures(r).find("run r2: energy_error_max = 0.0078 >= 0.0078 (by 0"), std::string::npos) << all_failures(r);
}

TEST(Gates, PenetrationOnContactSchemes) {
  const std::string toml = R"(
    [[gate]]
    name = "no penetration"
    kind = "max"
    column = "penetration_max"
    limit = %LIMIT%
    where = { scheme = ["semi_explicit", "implicit"], status = "ok" }
  )";
  auto with = [&](const std::string& limit) {
    std::string s = toml;
    s.replace(s.find("%LIMIT%"), 7, limit);
    return one(sweep(), s);
  };
  EXPECT_TRUE(with("1e-9").passed);
  const auto r = with("1e-13");
  EXPECT_FALSE(r.passed);
  ASSERT_EQ(r.failures.size(), 1u);
  EXPECT_EQ(r.failures[0], "run r5: penetration_max = 1e-12 > 1e-13 (by 9e-13, 900 %)");
}

TEST(Gates, MinPassesAndFails) {
  const std::string base = R"(
    [[gate]]
    name = "timed"
    kind = "min"
    column = "wall_seconds"
    where = { status = "ok" }
  )";
  EXPECT_TRUE(one(sweep(), base + "limit = 0.01\n").passed);
  const auto r = one(sweep(), base + "limit = 0.1\n");
  EXPECT_FALSE(r.passed);
  ASSERT_EQ(r.failures.size(), 1u);
  EXPECT_EQ(r.failures[0], "run r2: wall_seconds = 0.036 < 0.1 (by 0.064, 64 %)");
}

TEST(Gates, MissingValueOrColumnFails) {
  // r1 diverged: no energy value.
  const auto empty = one(sweep(), R"(
    [[gate]]
    name = "energy everywhere"
    kind = "max"
    column = "energy_error_max"
    limit = 0.02
    where = { mesh = "M1" }
  )");
  EXPECT_FALSE(empty.passed);
  EXPECT_NE(all_failures(empty).find("run r1: energy_error_max is empty"), std::string::npos) << all_failures(empty);

  const auto typo = one(sweep(), R"(
    [[gate]]
    name = "typo"
    kind = "max"
    column = "energy_eror_max"
    limit = 0.02
  )");
  EXPECT_FALSE(typo.passed);
  EXPECT_NE(all_failures(typo).find("column 'energy_eror_max' (the gate's column) is not in sweep/summary.csv"),
            std::string::npos)
      << all_failures(typo);

  const auto selector_typo = one(sweep(), R"(
    [[gate]]
    name = "typo"
    kind = "count"
    max = 0
    where = { stauts = "failed" }
  )");
  EXPECT_FALSE(selector_typo.passed);
  EXPECT_NE(all_failures(selector_typo).find("column 'stauts' (in where)"), std::string::npos);

  std::string csv = kSweep;
  csv.replace(csv.find("0.0078"), 6, "n/a");
  const auto text = one(parse_csv(csv, "s.csv"), R"(
    [[gate]]
    name = "energy"
    kind = "max"
    column = "energy_error_max"
    limit = 0.02
    where = { status = "ok" }
  )");
  EXPECT_FALSE(text.passed);
  EXPECT_NE(all_failures(text).find("run r2: energy_error_max = 'n/a' is not a number"), std::string::npos);
}

TEST(Gates, NanFailsAMaxGate) {
  std::string csv = kSweep;
  csv.replace(csv.find("0.0078"), 6, "nan");
  const auto r = one(parse_csv(csv, "s.csv"), R"(
    [[gate]]
    name = "energy"
    kind = "max"
    column = "energy_error_max"
    limit = 0.02
    where = { run_id = "r2" }
  )");
  EXPECT_FALSE(r.passed);
  EXPECT_NE(all_failures(r).find("run r2: energy_error_max = nan, not <= 0.02"), std::string::npos) << all_failures(r);
}

// ----------------------------------------------------------------------------------------------
// Selectors

TEST(Gates, NumericSelectorsCompareNumbers) {
  // 1e-6 in the gate file matches "1e-06" (r4, r5) and "0.000001" (r3); the string "1e-6" too.
  for (const char* value : {"1e-6", "0.000001", "\"1e-6\"", "1.0e-6"}) {
    const auto r = one(sweep(), std::string(R"(
      [[gate]]
      name = "dt 1e-6"
      kind = "count"
      min = 3
      max = 3
      where = { "time.dt" = )") + value + " }\n");
    EXPECT_TRUE(r.passed) << value << ": " << all_failures(r);
    EXPECT_EQ(r.checked_rows, 3);
  }
  // Dotted bare keys are the same column as the quoted key.
  const auto dotted = one(sweep(), R"(
    [[gate]]
    name = "dt"
    kind = "count"
    min = 2
    max = 2
    where = { time.dt = 1e-6, mesh = "M2" }
  )");
  EXPECT_TRUE(dotted.passed) << all_failures(dotted);
  // Text compares as text: "M1" is not "m1".
  const auto text = one(sweep(), R"(
    [[gate]]
    name = "m1"
    kind = "count"
    min = 1
    where = { mesh = "m1" }
  )");
  EXPECT_FALSE(text.passed);
  EXPECT_NE(all_failures(text).find("0 rows match {mesh = m1} < min 1 (by 1)"), std::string::npos) << all_failures(text);
}

TEST(Gates, AnyOfSelector) {
  const auto r = one(sweep(), R"(
    [[gate]]
    name = "any"
    kind = "count"
    min = 4
    max = 4
    where = { "time.dt" = [1e-5, 1e-4, 1e-6], mesh = ["M1", "M9"] , status = ["ok", "diverged"] }
  )");
  EXPECT_FALSE(r.passed);  // M1 has 3 runs
  EXPECT_NE(all_failures(r).find("3 rows match"), std::string::npos) << all_failures(r);
  EXPECT_NE(all_failures(r).find("run r1, run r2, run r3"), std::string::npos) << all_failures(r);
}

TEST(Gates, EmptySelectionFailsUnlessAllowed) {
  const std::string base = R"(
    [[gate]]
    name = "M3 energy"
    kind = "max"
    column = "energy_error_max"
    limit = 0.02
    where = { mesh = "M3" }
  )";
  const auto r = one(sweep(), base);
  EXPECT_FALSE(r.passed);
  EXPECT_EQ(r.checked_rows, 0);
  EXPECT_NE(all_failures(r).find("no row matches where {mesh = M3}"), std::string::npos) << all_failures(r);
  EXPECT_NE(describe(r).find("FAIL M3 energy: "), std::string::npos);

  const auto allowed = one(sweep(), base + "allow_empty = true\n");
  EXPECT_TRUE(allowed.passed);
  EXPECT_EQ(describe(allowed).rfind("PASS M3 energy (0 rows)", 0), 0u) << describe(allowed);

  // Against an empty table (a header only), every kind that selects rows fails.
  const CsvTable empty = parse_csv("run_id,status,energy_error_max\n", "empty.csv");
  EXPECT_FALSE(one(empty, R"(
    [[gate]]
    kind = "max"
    column = "energy_error_max"
    limit = 0.02
  )").passed);
}

// ----------------------------------------------------------------------------------------------
// pattern

const char* const kPattern = R"(
  [[gate]]
  name = "Table 1 pattern"
  kind = "pattern"
  cells = [
    { where = { mesh = "M1", "time.dt" = 1e-4, scheme = "semi_explicit" }, expect = "diverged" },
    { where = { mesh = "M1", "time.dt" = 1e-5, scheme = "semi_explicit" }, expect = "ok" },
    { where = { mesh = "M1", "time.dt" = 1e-6, scheme = "semi_explicit" }, expect = "ok" },
    { where = { mesh = "M2", "time.dt" = 1e-6, scheme = "semi_explicit" }, expect = "ok" },
    { where = { mesh = "M2", "time.dt" = 1e-6, scheme = "implicit" }, expect = "%EXPECT%" },
  ]
)";

GateResult pattern(const CsvTable& t, const std::string& expect) {
  std::string s = kPattern;
  s.replace(s.find("%EXPECT%"), 8, expect);
  return one(t, s);
}

TEST(Gates, PatternPasses) {
  const auto r = pattern(sweep(), "ok");
  EXPECT_TRUE(r.passed) << all_failures(r);
  EXPECT_EQ(r.checked_rows, 5);
}

TEST(Gates, PatternFailsOnAWrongStatus) {
  const auto r = pattern(sweep(), "diverged");
  EXPECT_FALSE(r.passed);
  ASSERT_EQ(r.failures.size(), 1u);
  EXPECT_EQ(r.failures[0],
            "cell {mesh = M2, time.dt = 1e-06, scheme = implicit}: run r5 status = ok, expected diverged");
  EXPECT_NE(describe(r).find("FAIL Table 1 pattern: "), std::string::npos);

  // A run that should have been stable but diverged reports its reason.
  std::string csv = kSweep;
  csv.replace(csv.find("r2,table1,ok,"), 13, "r2,table1,diverged,\"inverted element, step 7\"");
  const auto d = pattern(parse_csv(csv, "s.csv"), "ok");
  EXPECT_FALSE(d.passed);
  EXPECT_NE(all_failures(d).find("run r2 status = diverged, expected ok (reason: inverted element, step 7)"),
            std::string::npos)
      << all_failures(d);
}

TEST(Gates, PatternCellMustMatchExactlyOneRow) {
  std::string csv = kSweep;
  csv += "r7,table1,ok,,M1,1e-5,semi_explicit,0.0078,0,1,1,ok,\n";  // a repeated run
  const auto twice = pattern(parse_csv(csv, "s.csv"), "ok");
  EXPECT_FALSE(twice.passed);
  EXPECT_NE(all_failures(twice).find("cell {mesh = M1, time.dt = 1e-05, scheme = semi_explicit} matches 2 rows "
                                     "(run r2, run r7); expected exactly one"),
            std::string::npos)
      << all_failures(twice);

  std::string missing = kSweep;
  missing.erase(missing.find("r3,"), missing.find("r4,") - missing.find("r3,"));
  const auto none = pattern(parse_csv(missing, "s.csv"), "ok");
  EXPECT_FALSE(none.passed);
  EXPECT_NE(all_failures(none).find("cell {mesh = M1, time.dt = 1e-06, scheme = semi_explicit} matches no row"),
            std::string::npos)
      << all_failures(none);
}

// ----------------------------------------------------------------------------------------------
// near

TEST(Gates, NearPassesAndFails) {
  const std::string base = R"(
    [[gate]]
    name = "von Mises vs paper"
    kind = "near"
    column = "von_mises_max"
    reference = 9.438e5
    where = { mesh = "M2", "time.dt" = 1e-6, scheme = "semi_explicit" }
  )";
  const auto ok = one(sweep(), base + "rel_tolerance = 0.15\n");
  EXPECT_TRUE(ok.passed) << all_failures(ok);
  EXPECT_EQ(ok.checked_rows, 1);
  ASSERT_EQ(ok.notes.size(), 1u);
  EXPECT_NE(ok.notes[0].find("run r4: von_mises_max = 847900, reference 943800: difference -9.59e+04 (-10.2 %)"),
            std::string::npos)
      << ok.notes[0];

  const auto bad = one(sweep(), base + "rel_tolerance = 0.05\n");
  EXPECT_FALSE(bad.passed);
  ASSERT_EQ(bad.failures.size(), 1u);
  EXPECT_EQ(bad.failures[0],
            "run r4: von_mises_max = 847900, reference 943800: difference -9.59e+04 (-10.2 %) exceeds the "
            "allowed +-4.72e+04 (rel_tolerance 0.05 x |reference|) by 4.87e+04");

  // Absolute tolerance; either tolerance suffices when both are given.
  EXPECT_FALSE(one(sweep(), base + "tolerance = 5e4\n").passed);
  EXPECT_TRUE(one(sweep(), base + "tolerance = 1e5\n").passed);
  EXPECT_TRUE(one(sweep(), base + "tolerance = 1e5\nrel_tolerance = 0.01\n").passed);
}

// ----------------------------------------------------------------------------------------------
// ratio

TEST(Gates, RatioPassesAndFails) {
  const std::string base = R"(
    [[gate]]
    name = "implicit cost"
    kind = "ratio"
    column = "wall_seconds"
    where = { mesh = "M2", "time.dt" = 1e-6 }
    numerator = { scheme = "implicit" }
    denominator = { scheme = "semi_explicit" }
  )";
  const auto ok = one(sweep(), base + "floor = 5.0\n");
  EXPECT_TRUE(ok.passed) << all_failures(ok);
  EXPECT_EQ(ok.checked_rows, 2);
  ASSERT_EQ(ok.notes.size(), 1u);
  EXPECT_NE(ok.notes[0].find("wall_seconds ratio run r5 / run r4 = 12.5 / 1.06 = 11.8 >= floor 5"), std::string::npos)
      << ok.notes[0];

  const auto low = one(sweep(), base + "floor = 20.0\n");
  EXPECT_FALSE(low.passed);
  ASSERT_EQ(low.failures.size(), 1u);
  EXPECT_EQ(low.failures[0], "wall_seconds ratio run r5 / run r4 = 12.5 / 1.06 = 11.8 < floor 20 (by 8.21, 41 %)");

  const auto high = one(sweep(), base + "floor = 1\nceiling = 10\n");
  EXPECT_FALSE(high.passed);
  EXPECT_NE(all_failures(high).find("= 11.8 > ceiling 10 (by 1.79, 17.9 %)"), std::string::npos) << all_failures(high);
}

TEST(Gates, RatioSelectorsMustMatchOneRowEach) {
  const auto r = one(sweep(), R"(
    [[gate]]
    name = "ambiguous"
    kind = "ratio"
    column = "wall_seconds"
    numerator = { scheme = "implicit" }
    denominator = { scheme = "explicit" }
    floor = 1
  )");
  EXPECT_FALSE(r.passed);
  EXPECT_NE(all_failures(r).find("numerator {scheme = implicit} matches 2 rows (run r5, run r6); expected exactly one"),
            std::string::npos)
      << all_failures(r);
  EXPECT_NE(all_failures(r).find("denominator {scheme = explicit} matches no row"), std::string::npos);

  // A failed run has no time: the ratio cannot pass.
  const auto missing = one(sweep(), R"(
    [[gate]]
    name = "failed run"
    kind = "ratio"
    column = "wall_seconds"
    numerator = { run_id = "r6" }
    denominator = { run_id = "r4" }
    floor = 1
  )");
  EXPECT_FALSE(missing.passed);
  EXPECT_NE(all_failures(missing).find("numerator run r6: wall_seconds is empty"), std::string::npos);
}

// ----------------------------------------------------------------------------------------------
// count, require_rows

TEST(Gates, CountPassesAndFails) {
  const auto fails = one(sweep(), R"(
    [[gate]]
    name = "no failed runs"
    kind = "count"
    where = { status = "failed" }
    max = 0
  )");
  EXPECT_FALSE(fails.passed);
  ASSERT_EQ(fails.failures.size(), 1u);
  EXPECT_EQ(fails.failures[0], "1 row matches {status = failed} > max 0 (by 1): run r6");

  const auto passes = one(sweep(), R"(
    [[gate]]
    name = "two diverged or fewer"
    kind = "count"
    where = { status = "diverged" }
    max = 2
  )");
  EXPECT_TRUE(passes.passed);
  EXPECT_EQ(describe(passes), "PASS two diverged or fewer (1 row)");
}

TEST(Gates, RequireRows) {
  const std::string gate = R"(
    [[gate]]
    name = "stable"
    kind = "count"
    min = 1
    where = { status = "ok" }
  )";
  auto results = evaluate_gates(sweep(), gates("require_rows = 6\n" + gate));
  ASSERT_EQ(results.size(), 2u);
  EXPECT_EQ(results[0].name, "require_rows");
  EXPECT_TRUE(results[0].passed);
  results = evaluate_gates(sweep(), gates("require_rows = 12\n" + gate));
  EXPECT_FALSE(results[0].passed);
  EXPECT_EQ(results[0].failures.at(0), "sweep/summary.csv has 6 rows < require_rows 12 (by 6)");
  EXPECT_TRUE(results[1].passed);
}

TEST(Gates, DefaultNameNamesKindAndColumn) {
  const auto r = one(sweep(), "[[gate]]\nkind = \"max\"\ncolumn = \"penetration_max\"\nlimit = 1e-9\nwhere = { status = \"ok\" }\n");
  EXPECT_EQ(r.name, "gate[0] max penetration_max");
}

// ----------------------------------------------------------------------------------------------
// Bad gate files

TEST(GateFile, RejectsBadFilesNamingFileLineAndKey) {
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"maximum\"\ncolumn = \"a\"\nlimit = 1\n",
                  {"ci/gates/bad.toml:3: gate[0].kind: got \"maximum\"; allowed: \"max\", \"min\", \"near\""});
  expect_rejected("[[gate]]\nname = \"x\"\ncolumn = \"a\"\n",
                  {"ci/gates/bad.toml:1: gate[0].kind: missing required key"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"max\"\ncolumn = \"a\"\nlimit = 1\nlimt = 2\n",
                  {"ci/gates/bad.toml:6: gate[0].limt: unknown key (did you mean \"limit\"?); allowed here:", "strict"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"max\"\nlimit = 1\n",
                  {"ci/gates/bad.toml:1: gate[0].column: missing required key"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"max\"\ncolumn = \"\"\nlimit = 1\n",
                  {"ci/gates/bad.toml:4: gate[0].column: expected a column name"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"max\"\ncolumn = \"a\"\nlimit = \"0.02\"\n",
                  {"ci/gates/bad.toml:5: gate[0].limit: expected a finite number; got a string"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"max\"\ncolumn = \"a\"\n",
                  {"gate[0].limit: missing required key"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"count\"\nmax = 0\nallow_empty = true\n",
                  {"ci/gates/bad.toml:5: gate[0].allow_empty: unknown key"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"near\"\ncolumn = \"a\"\nreference = 1\n",
                  {"gate[0].rel_tolerance: missing: a near gate needs tolerance"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"near\"\ncolumn = \"a\"\nreference = 1\ntolerance = -1\n",
                  {"ci/gates/bad.toml:6: gate[0].tolerance: expected a number >= 0"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"ratio\"\ncolumn = \"a\"\nnumerator = {run_id = \"a\"}\n"
                  "denominator = {run_id = \"b\"}\nfloor = 3\nceiling = 2\n",
                  {"ci/gates/bad.toml:8: gate[0].ceiling: ceiling 2 is below floor 3"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"ratio\"\ncolumn = \"a\"\ndenominator = {run_id = \"b\"}\nfloor = 3\n",
                  {"gate[0].numerator: missing required key"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"count\"\n", {"gate[0].max: missing: a count gate needs min or max"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"count\"\nmax = -1\n",
                  {"ci/gates/bad.toml:4: gate[0].max: expected an integer in [0, "});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"count\"\nmax = 1\nwhere = { status = { a = [] } }\n",
                  {"ci/gates/bad.toml:5: gate[0].where.status.a: expected a string, a number, a boolean or a "
                   "non-empty array"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"count\"\nmax = 1\nwhere = \"status = ok\"\n",
                  {"ci/gates/bad.toml:5: gate[0].where: expected a table"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"pattern\"\ncells = []\n",
                  {"ci/gates/bad.toml:4: gate[0].cells: expected at least one cell"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"pattern\"\ncells = [ { where = { mesh = \"M1\" }, expected = \"ok\" } ]\n",
                  {"ci/gates/bad.toml:4: gate[0].cells[0].expected: unknown key (did you mean \"expect\"? it is required here and missing)"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"pattern\"\ncells = [ { expect = \"ok\" } ]\n",
                  {"gate[0].cells[0].where: missing required key"});
  expect_rejected("[[gate]]\nname = \"x\"\nkind = \"count\"\nmax = 0\n[[gate]]\nname = \"x\"\nkind = \"count\"\nmax = 1\n",
                  {"ci/gates/bad.toml:6: gate[1].name: duplicate gate name \"x\" (also gate[0])"});
  expect_rejected("name = \"suite\"\n", {"ci/gates/bad.toml:1: gate: no [[gate]] tables"});
  expect_rejected("requre_rows = 3\n[[gate]]\nkind = \"count\"\nmax = 0\n",
                  {"ci/gates/bad.toml:1: requre_rows: unknown key (did you mean \"require_rows\"?); allowed here:"});
  expect_rejected("[[gate]\nkind = 1\n", {"ci/gates/bad.toml:1: TOML syntax error"});
}

TEST(GateFile, ReadsFilesAndDefaults) {
  TempDir dir;
  const fs::path p = dir.write("ci/gates/oblique_plate.toml", std::string("require_rows = 6\n") + kPattern);
  const GateFile g = read_gates(p);
  EXPECT_EQ(g.name, "oblique_plate");
  EXPECT_EQ(g.require_rows, 6);
  ASSERT_EQ(g.gates.size(), 1u);
  EXPECT_EQ(g.gates[0].kind, GateKind::pattern);
  EXPECT_EQ(g.gates[0].column, "status");
  EXPECT_EQ(g.gates[0].cells.size(), 5u);
  EXPECT_EQ(g.gates[0].location, p.string() + ":3");
  EXPECT_THROW(read_gates(dir.path() / "missing.toml"), InputError);
}

TEST(GateFile, IncludeSharesGatesBetweenFiles) {
  // Two gate files that share most of their gates: the shared ones in common.toml, included
  // (paths relative to the including file) ahead of each file's own gates.
  TempDir dir;
  dir.write("ci/gates/shared/common.toml",
            "name = \"common\"\n"
            "[[gate]]\nname = \"no failed runs\"\nkind = \"count\"\nwhere = { status = \"failed\" }\nmax = 0\n");
  dir.write("ci/gates/shared/energy.toml",
            "include = \"common.toml\"\n"
            "[[gate]]\nname = \"energy\"\nkind = \"max\"\ncolumn = \"energy_error_max\"\nlimit = 0.02\n"
            "where = { status = \"ok\" }\n");
  const fs::path fast = dir.write("ci/gates/fast.toml",
                                  "require_rows = 6\ninclude = [\"shared/energy.toml\"]\n"
                                  "[[gate]]\nname = \"own\"\nkind = \"count\"\nwhere = { mesh = \"M2\" }\nmin = 2\n");
  const GateFile g = read_gates(fast);
  EXPECT_EQ(g.name, "fast");
  EXPECT_EQ(g.require_rows, 6);
  ASSERT_EQ(g.gates.size(), 3u);
  EXPECT_EQ(g.gates[0].name, "no failed runs");  // innermost first, then in include order
  EXPECT_EQ(g.gates[1].name, "energy");
  EXPECT_EQ(g.gates[2].name, "own");
  // Each gate's location names the file it is written in.
  EXPECT_NE(g.gates[0].location.find("common.toml:2"), std::string::npos) << g.gates[0].location;
  // They are evaluated like the file's own: r6 failed, so the shared count gate fails.
  const std::vector<GateResult> r = evaluate_gates(sweep(), g);
  ASSERT_EQ(r.size(), 4u);
  EXPECT_TRUE(r[0].passed);   // require_rows
  EXPECT_FALSE(r[1].passed);  // no failed runs
  EXPECT_TRUE(r[2].passed);
  EXPECT_TRUE(r[3].passed);

  auto rejects = [&](const std::string& name, const std::string& text, const std::vector<std::string>& pieces) {
    const fs::path p = dir.write(name, text);
    try {
      read_gates(p);
      ADD_FAILURE() << name << ": accepted";
    } catch (const InputError& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
      for (const auto& piece : pieces) EXPECT_NE(m.find(piece), std::string::npos) << "'" << piece << "' not in: " << m;
    }
  };
  const std::string own = "[[gate]]\nname = \"own\"\nkind = \"count\"\nmax = 9\n";
  rejects("ci/gates/missing_include.toml", "include = \"nowhere.toml\"\n" + own,
          {"missing_include.toml:1: include: cannot open gate file", "nowhere.toml"});
  dir.write("ci/gates/cycle_b.toml", "include = \"cycle_a.toml\"\n[[gate]]\nname = \"b\"\nkind = \"count\"\nmax = 9\n");
  rejects("ci/gates/cycle_a.toml", "include = \"cycle_b.toml\"\n" + own, {"cycle_b.toml:1: include:", "include cycle"});
  rejects("ci/gates/dup.toml", "include = \"shared/common.toml\"\n[[gate]]\nname = \"no failed runs\"\nkind = \"count\"\nmax = 1\n",
          {"dup.toml:3: gate[0].name: duplicate gate name \"no failed runs\"", "common.toml"});
  dir.write("ci/gates/shared/rows.toml", "require_rows = 3\n" + own);
  rejects("ci/gates/rows.toml", "include = \"shared/rows.toml\"\n[[gate]]\nname = \"x\"\nkind = \"count\"\nmax = 1\n",
          {"rows.toml:1: require_rows:", "included"});
  rejects("ci/gates/bad_include.toml", "include = 3\n" + own, {"include: expected a string or an array of non-empty strings"});
}

// ----------------------------------------------------------------------------------------------
// JUnit XML

TEST(Junit, WellFormedOneTestcasePerGateWithFailures) {
  std::string csv = kSweep;
  csv.replace(csv.find("r4,"), 2, "\"<r4 & \"\"x\"\">\"");  // a run id that needs escaping
  const CsvTable t = parse_csv(csv, "s.csv");
  const GateFile g = gates(R"(
    name = "oblique <plate> & \"friends\""
    require_rows = 2
    [[gate]]
    name = "energy < 0.001 & 'strict'"
    kind = "max"
    column = "energy_error_max"
    limit = 0.001
    where = { status = "ok" }
    [[gate]]
    name = "no failed runs"
    kind = "count"
    max = 0
    where = { status = "failed" }
    [[gate]]
    name = "stable"
    kind = "count"
    min = 1
    where = { status = "ok" }
  )");
  const auto results = evaluate_gates(t, g);
  const std::string xml = junit_xml(results, g.name, 0.25);
  XmlElement root;
  try {
    root = XmlReader(xml).document();
  } catch (const std::exception& e) {
    FAIL() << "not well formed: " << e.what() << "\n" << xml;
  }
  EXPECT_EQ(root.name, "testsuites");
  EXPECT_EQ(root.attrs["tests"], "4");
  EXPECT_EQ(root.attrs["failures"], "2");
  ASSERT_EQ(root.children.size(), 1u);
  const XmlElement& suite = root.children[0];
  EXPECT_EQ(suite.name, "testsuite");
  EXPECT_EQ(suite.attrs.at("name"), "oblique <plate> & \"friends\"");
  EXPECT_EQ(suite.attrs.at("time"), "0.250");
  EXPECT_EQ(suite.attrs.at("failures"), "2");
  ASSERT_EQ(suite.children.size(), 4u);
  std::vector<std::string> names;
  for (const auto& tc : suite.children) {
    EXPECT_EQ(tc.name, "testcase");
    names.push_back(tc.attrs.at("name"));
  }
  EXPECT_EQ(names, (std::vector<std::string>{"require_rows", "energy < 0.001 & 'strict'", "no failed runs", "stable"}));

  auto failure_of = [](const XmlElement& tc) -> const XmlElement* {
    for (const auto& c : tc.children)
      if (c.name == "failure") return &c;
    return nullptr;
  };
  EXPECT_EQ(failure_of(suite.children[0]), nullptr);
  EXPECT_EQ(failure_of(suite.children[3]), nullptr);
  const XmlElement* energy = failure_of(suite.children[1]);
  ASSERT_NE(energy, nullptr);
  EXPECT_NE(energy->attrs.at("message").find("run <r4 & \"x\">: energy_error_max = 0.0025 > 0.001 (by 0.0015, 150 %)"),
            std::string::npos)
      << energy->attrs.at("message");
  EXPECT_NE(energy->text.find("run r2: energy_error_max = 0.0078 > 0.001"), std::string::npos);
  EXPECT_NE(energy->text.find('\n'), std::string::npos);  // one failure per line
  const XmlElement* failed = failure_of(suite.children[2]);
  ASSERT_NE(failed, nullptr);
  EXPECT_NE(failed->attrs.at("message").find("run r6"), std::string::npos);
}

TEST(Junit, ControlCharactersAndBadUtf8AreReplaced) {
  GateResult r;
  r.name = std::string("bell\x07 and \xFF byte, \xC3\xA9 kept");
  r.passed = false;
  r.failures = {"line one\nline two"};
  const std::string xml = junit_xml({r}, "s", 1.0);
  EXPECT_EQ(xml.find('\x07'), std::string::npos);
  EXPECT_EQ(xml.find('\xFF'), std::string::npos);
  EXPECT_NE(xml.find("\xC3\xA9 kept"), std::string::npos);
  EXPECT_NE(xml.find("message=\"line one&#10;line two\""), std::string::npos) << xml;
  EXPECT_NO_THROW(XmlReader(xml).document());
}

// ----------------------------------------------------------------------------------------------
// ricochet check

const char* const kGoodGates = R"(
  name = "oblique_plate"
  require_rows = 6
  [[gate]]
  name = "energy bound on stable runs"
  kind = "max"
  column = "energy_error_max"
  limit = 0.02
  strict = true
  where = { status = "ok" }
  [[gate]]
  name = "no penetration"
  kind = "max"
  column = "penetration_max"
  limit = 1e-9
  where = { status = "ok", scheme = ["semi_explicit", "implicit"] }
  [[gate]]
  name = "implicit slower than semi-explicit on M2 at 1e-6"
  kind = "ratio"
  column = "wall_seconds"
  numerator = { mesh = "M2", "time.dt" = 1e-6, scheme = "implicit" }
  denominator = { mesh = "M2", "time.dt" = 1e-6, scheme = "semi_explicit" }
  floor = 5.0
)";

TEST(CheckCommand, ExitZeroWhenAllGatesPass) {
  TempDir dir;
  const fs::path csv = dir.write("sweep/summary.csv", kSweep);
  const fs::path toml = dir.write("gates.toml", kGoodGates);
  std::ostringstream out, err;
  EXPECT_EQ(check_command({csv.string(), toml.string()}, out, err), 0) << out.str() << err.str();
  EXPECT_EQ(err.str(), "");
  const std::string o = out.str();
  EXPECT_NE(o.find("PASS require_rows (6 rows)\n"), std::string::npos) << o;
  EXPECT_NE(o.find("PASS energy bound on stable runs (4 rows)"), std::string::npos) << o;
  EXPECT_NE(o.find("PASS implicit slower than semi-explicit on M2 at 1e-6 (2 rows)"), std::string::npos) << o;
  EXPECT_NE(o.find("\ngates: 4 passed, 0 failed\n"), std::string::npos) << o;
  // JUnit next to the summary.
  const fs::path junit = dir.path() / "sweep" / "gates-junit.xml";
  ASSERT_TRUE(fs::exists(junit));
  std::ifstream in(junit);
  const std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const XmlElement root = XmlReader(xml).document();
  EXPECT_EQ(root.children.at(0).children.size(), 4u);
  EXPECT_EQ(root.attrs.at("failures"), "0");
  EXPECT_FALSE(fs::exists(junit.string() + ".tmp"));
}

TEST(CheckCommand, ExitFourWhenAGateFails) {
  TempDir dir;
  std::string bad = kSweep;
  bad.replace(bad.find("0.0025"), 6, "0.0312");
  const fs::path csv = dir.write("summary.csv", bad);
  const fs::path toml = dir.write("gates.toml", kGoodGates);
  const fs::path junit = dir.path() / "reports" / "junit.xml";
  std::ostringstream out, err;
  EXPECT_EQ(check_command({csv.string(), toml.string(), "--junit", junit.string()}, out, err), 4);
  const std::string o = out.str();
  EXPECT_NE(o.find("FAIL energy bound on stable runs: run r4: energy_error_max = 0.0312 >= 0.02 (by 0.0112, 56 %)\n"),
            std::string::npos)
      << o;
  EXPECT_NE(o.find("gates: 3 passed, 1 failed\n"), std::string::npos) << o;
  ASSERT_TRUE(fs::exists(junit));
  std::ifstream in(junit);
  const std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(xml.find("<failure"), std::string::npos);
  EXPECT_FALSE(fs::exists(dir.path() / "gates-junit.xml"));
}

TEST(CheckCommand, ExitTwoOnBadInputAndWritesNothing) {
  TempDir dir;
  const fs::path csv = dir.write("summary.csv", kSweep);
  const fs::path good = dir.write("gates.toml", kGoodGates);
  const fs::path bad = dir.write("bad.toml", "[[gate]]\nname = \"x\"\nkind = \"nearly\"\n");
  const fs::path bad_csv = dir.write("bad.csv", "a,b\n1,2,3\n");
  const fs::path junit = dir.path() / "gates-junit.xml";
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{csv.string(), bad.string()}, bad.string() + ":3: gate[0].kind: got \"nearly\""},
      {{bad_csv.string(), good.string()}, bad_csv.string() + ":2: row has 3 fields"},
      {{(dir.path() / "none.csv").string(), good.string()}, "none.csv: cannot read"},
      {{csv.string(), (dir.path() / "none.toml").string()}, "none.toml: cannot open gate file"},
      {{csv.string()}, "ricochet check: expected SUMMARY.csv and GATES.toml"},
      {{csv.string(), good.string(), "--junit"}, "--junit needs a value"},
      {{csv.string(), good.string(), "--bogus"}, "unknown option '--bogus'"},
  };
  for (const auto& c : cases) {
    std::ostringstream out, err;
    EXPECT_EQ(check_command(c.args, out, err), 2) << c.message;
    const std::string e = err.str();
    EXPECT_EQ(e.rfind("ricochet: ", 0), 0u) << e;
    EXPECT_NE(e.find(c.message), std::string::npos) << e;
    EXPECT_EQ(std::count(e.begin(), e.end(), '\n'), 1) << e;
    EXPECT_EQ(out.str(), "");
    EXPECT_FALSE(fs::exists(junit)) << c.message;
  }
}

TEST(CheckCommand, ExitOneWhenTheReportCannotBeWritten) {
  TempDir dir;
  const fs::path csv = dir.write("summary.csv", kSweep);
  const fs::path toml = dir.write("gates.toml", kGoodGates);
  dir.write("file", "x");
  std::ostringstream out, err;
  EXPECT_EQ(check_command({csv.string(), toml.string(), "--junit=" + (dir.path() / "file" / "j.xml").string()}, out, err), 1);
  EXPECT_NE(err.str().find("ricochet: error: cannot write"), std::string::npos) << err.str();
}

}  // namespace
}  // namespace ricochet
