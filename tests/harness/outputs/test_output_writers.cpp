// The output layer: JSON, CSV, VTU/PVD text and the atomic file writer.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <fstream>
#include <limits>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "harness/input/mesh_generators3.hpp"
#include "harness/outputs/atomic_file.hpp"
#include "harness/outputs/csv_writer.hpp"
#include "harness/outputs/json_io.hpp"
#include "harness/outputs/vtu_writer.hpp"
#include "tests/support/temp_dir.hpp"

#include <zlib.h>

namespace ricochet {
namespace {

namespace fs = std::filesystem;
constexpr double nan_value = std::numeric_limits<double>::quiet_NaN();
constexpr double inf_value = std::numeric_limits<double>::infinity();

// Doubles whose shortest text is easy to get wrong: subnormal minimum, largest finite, -0.
const std::vector<double> awkward = {0.1,        1e-300,   5e-324, 1.7976931348623157e308,
                                     -0.0,       1.0 / 3.0, 2.2250738585072014e-308,
                                     123456789012345680.0, -1e22, 9007199254740993.0};

void expect_same_bits(const std::string& text, double expected) {
  char* end = nullptr;
  const double parsed = std::strtod(text.c_str(), &end);
  EXPECT_EQ(*end, '\0') << "trailing characters in '" << text << "'";
  EXPECT_EQ(std::bit_cast<std::uint64_t>(parsed), std::bit_cast<std::uint64_t>(expected))
      << "'" << text << "' does not round-trip";
}

// ---------------------------------------------------------------- JSON

TEST(Json, ExactOutputForSmallDocument) {
  Json doc = Json::object();
  doc["name"] = "first";
  doc["steps"] = 1200;
  doc["dt"] = 1e-7;
  doc["ok"] = true;
  doc["missing"] = nullptr;
  doc["energy"]["kinetic"] = 0.5;  // a null member becomes an object
  doc["energy"]["internal"] = nan_value;
  doc["list"].push_back(1);  // ... or an array
  doc["list"].push_back(-2.5);
  doc["list"].push_back(Json::object());
  doc["list"].push_back(Json::array({false}));
  doc["extremes"].push_back(std::numeric_limits<std::int64_t>::min());
  doc["extremes"].push_back(std::numeric_limits<std::uint64_t>::max());
  doc["extremes"].push_back(-inf_value);
  doc["extremes"].push_back(2.0);
  doc["name"] = "taylor_bar";  // assigning an existing key keeps its place
  EXPECT_EQ(doc.size(), 8u);
  EXPECT_EQ(dump_json(doc),
            "{\n"
            "  \"name\": \"taylor_bar\",\n"
            "  \"steps\": 1200,\n"
            "  \"dt\": 1e-07,\n"
            "  \"ok\": true,\n"
            "  \"missing\": null,\n"
            "  \"energy\": {\n"
            "    \"kinetic\": 0.5,\n"
            "    \"internal\": null\n"
            "  },\n"
            "  \"list\": [\n"
            "    1,\n"
            "    -2.5,\n"
            "    {},\n"
            "    [\n"
            "      false\n"
            "    ]\n"
            "  ],\n"
            "  \"extremes\": [\n"
            "    -9223372036854775808,\n"
            "    18446744073709551615,\n"
            "    null,\n"
            "    2.0\n"
            "  ]\n"
            "}\n");
  EXPECT_EQ(dump_json(Json::object()), "{}\n");
  EXPECT_EQ(dump_json(Json::array()), "[]\n");
  EXPECT_EQ(dump_json(Json()), "null\n");
}

TEST(Json, EscapesStringsAndKeys) {
  const std::string nasty = std::string("q\"b\\s/\n\t\x01\x1f", 10) + std::string(1, '\0') + "é";
  EXPECT_EQ(dump_json(Json(nasty)), "\"q\\\"b\\\\s/\\n\\t\\u0001\\u001f\\u0000é\"\n");
  Json doc;
  doc["a\"b"] = "x";
  EXPECT_EQ(dump_json(doc), "{\n  \"a\\\"b\": \"x\"\n}\n");
  // Bytes that are not UTF-8 do not stop the output.
  EXPECT_EQ(dump_json(Json("a\xff" "b")), "\"a\xEF\xBF\xBD" "b\"\n");
}

// Every double written parses back to the same bits, and stays a double (never an integer).
TEST(Json, DoublesRoundTripBitForBit) {
  for (const double value : awkward) {
    std::string text = dump_json(Json(value));
    ASSERT_EQ(text.back(), '\n');
    text.pop_back();
    expect_same_bits(text, value);
    const Json back = parse_json(text);
    ASSERT_TRUE(back.is_number_float()) << text;
    EXPECT_EQ(std::bit_cast<std::uint64_t>(back.get<double>()), std::bit_cast<std::uint64_t>(value)) << text;
    // As summary.csv shows it: the CSV form of the same double.
    std::string csv;
    append_number(csv, value);
    EXPECT_EQ(compact_json(back), csv) << text;
  }
  EXPECT_EQ(dump_json(Json(-0.0)), "-0.0\n");
  EXPECT_EQ(dump_json(Json(5e-324)), "5e-324\n");
  EXPECT_EQ(dump_json(Json(1.7976931348623157e308)), "1.7976931348623157e+308\n");
}

TEST(Json, ParsesInDocumentOrderWithCompactText) {
  const Json v = parse_json(
      R"( {"z": 1, "b": [true, false, null, -0.5e-3, 2.0], "c": {"d": "x\"\\\/\b\f\n\r\t\u00e9\ud83d\ude00"}, "e": 12345678901234567890} )");
  ASSERT_TRUE(v.is_object());
  std::vector<std::string> keys;
  for (const auto& [key, value] : v.items()) keys.push_back(key);
  EXPECT_EQ(keys, (std::vector<std::string>{"z", "b", "c", "e"}));
  EXPECT_EQ(v["c"]["d"].get<std::string>(), "x\"\\/\b\f\n\r\t\xC3\xA9\xF0\x9F\x98\x80");
  EXPECT_EQ(compact_json(v), R"({"z":1,"b":[true,false,null,-5e-04,2],"c":{"d":"x\"\\/\b\f\n\r\té😀"},"e":12345678901234567890})");
  EXPECT_EQ(compact_json(parse_json(dump_json(v))), compact_json(v));
  for (const char* bad : {"", "{", "[1,]", "{\"a\":1,}", "01", "1.", "-", "1e", "\"abc", "\"a\nb\"", "\"\\x\"",
                          "\"\\ud800\"", "tru", "nul", "{} x", "{a:1}", "[1 2]", "'a'", "+1", ".5"})
    EXPECT_THROW(parse_json(bad), JsonParseError) << bad;
}

TEST(Json, FileErrorsAreOneLineNamingTheFile) {
  const fs::path dir = fs::temp_directory_path() / "ricochet_json_errors";
  fs::create_directories(dir);
  const fs::path bad = dir / "summary.json";
  std::ofstream(bad) << "{\n  \"a\": tru\n}\n";
  for (const fs::path& file : {bad, dir / "absent.json"}) {
    try {
      read_json_file(file);
      ADD_FAILURE() << file;
    } catch (const JsonParseError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(file.string() + ": ", 0), 0u) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
      EXPECT_NE(what.find(file == bad ? "parse error at line " : "cannot read"), std::string::npos) << what;
    }
  }
  fs::remove_all(dir);
}

// ---------------------------------------------------------------- CSV

TEST(CsvWriter, HeaderAndRows) {
  const std::vector<std::string> columns = {"t", "x,y", "say \"hi\""};
  const std::vector<double> rows = {0, 0.1, -0.0, 1e-300, -nan_value, -inf_value, inf_value, 2.5,
                                    5e-324};
  EXPECT_EQ(format_csv(columns, rows),
            "t,\"x,y\",\"say \"\"hi\"\"\"\n"
            "0,0.1,-0\n"
            "1e-300,nan,-inf\n"
            "inf,2.5,5e-324\n");
  EXPECT_EQ(format_csv({"only"}, {}), "only\n");
}

TEST(CsvWriter, NumbersRoundTrip) {
  std::istringstream lines(format_csv({"v"}, awkward));
  std::string line;
  std::getline(lines, line);
  for (const double value : awkward) {
    ASSERT_TRUE(std::getline(lines, line));
    expect_same_bits(line, value);
  }
}

TEST(CsvWriter, SizeCheck) {
  EXPECT_THROW(format_csv({"a", "b"}, {1, 2, 3}), std::invalid_argument);
  EXPECT_THROW(format_csv({}, {}), std::invalid_argument);
  EXPECT_NO_THROW(format_csv({"a", "b"}, {1, 2, 3, 4}));
}

TEST(CsvWriter, FieldQuoting) {
  EXPECT_EQ(csv_field("plain text"), "plain text");
  EXPECT_EQ(csv_field(""), "");
  EXPECT_EQ(csv_field("a,b"), "\"a,b\"");
  EXPECT_EQ(csv_field("a\"b"), "\"a\"\"b\"");
  EXPECT_EQ(csv_field("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(csv_field("cr\r"), "\"cr\r\"");
}

// ---------------------------------------------------------------- VTU / PVD

// "" if `xml` is well-formed as far as these writers need: one root element, every element
// closed in order, attribute values double-quoted, and every '&' one of the five XML entities.
std::string xml_error(const std::string& xml) {
  static const std::regex entity("^&(amp|lt|gt|quot|apos);");
  static const std::regex tag(
      R"(^<([A-Za-z_][\w.-]*)((?:\s+[A-Za-z_][\w.-]*="[^"<]*")*)\s*(/?)>$)");
  for (std::size_t i = xml.find('&'); i != std::string::npos; i = xml.find('&', i + 1)) {
    if (!std::regex_search(xml.substr(i, 6), entity)) return "bare & at " + std::to_string(i);
  }
  if (xml.rfind("<?xml version=\"1.0\"?>\n", 0) != 0) return "no XML declaration";
  std::vector<std::string> open;
  int roots = 0;
  for (std::size_t i = xml.find('>') + 1; i < xml.size();) {
    const std::size_t lt = xml.find('<', i);
    if (lt == std::string::npos) break;
    const std::size_t gt = xml.find('>', lt);
    if (gt == std::string::npos) return "unterminated tag";
    const std::string text = xml.substr(lt, gt - lt + 1);
    i = gt + 1;
    std::smatch m;
    if (text.rfind("</", 0) == 0) {
      const std::string name = text.substr(2, text.size() - 3);
      if (open.empty() || open.back() != name) return "unexpected " + text;
      open.pop_back();
    } else if (std::regex_match(text, m, tag)) {
      if (open.empty()) ++roots;
      if (m[3].length() == 0) open.push_back(m[1]);
    } else {
      return "malformed tag " + text;
    }
  }
  if (!open.empty()) return "unclosed <" + open.back() + ">";
  return roots == 1 ? "" : "expected one root element";
}

// The whitespace-separated values of the DataArray whose Name is `name`.
std::vector<std::string> array_values(const std::string& xml, const std::string& name) {
  const std::size_t at = xml.find("Name=\"" + name + "\"");
  if (at == std::string::npos) return {"<missing>"};
  const std::size_t begin = xml.find('>', at) + 1;
  std::istringstream values(xml.substr(begin, xml.find("</DataArray>", begin) - begin));
  std::vector<std::string> out;
  for (std::string value; values >> value;) out.push_back(value);
  return out;
}

VtuData mixed_mesh() {
  VtuData data;
  data.points.resize(2, 5);
  data.points << 0, 1, 1, 0, 2,  //
      0, 0, 1, 1, 0.5;
  data.quads = {{0, 1, 2, 3}};
  data.tris = {{1, 4, 2}};
  data.time = 0.25;
  Eigen::Matrix2Xd velocity(2, 5);
  velocity << 1, 2, 3, 4, 5,  //
      -1, -2, -3, -4, -5;
  data.point_vectors = {{"velocity", velocity}};
  data.point_scalars = {{"temperature", {300, 301, 302, 303, 304}}};
  data.cell_scalars = {{"pressure", {1.5, -2}}};
  data.cell_ints = {{"body", {0, 1}}};
  return data;
}

using Tokens = std::vector<std::string>;

TEST(VtuWriter, MixedMeshStructure) {
  const std::string xml = format_vtu(mixed_mesh());
  EXPECT_EQ(xml_error(xml), "");
  EXPECT_NE(xml.find("<VTKFile type=\"UnstructuredGrid\" version=\"0.1\""), std::string::npos);
  EXPECT_NE(xml.find("<Piece NumberOfPoints=\"5\" NumberOfCells=\"2\">"), std::string::npos);
  // FieldData belongs to the grid, not the piece (meshio rejects it inside <Piece>).
  EXPECT_LT(xml.find("<FieldData>"), xml.find("<Piece "));
  EXPECT_NE(xml.find("type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\""),
            std::string::npos);
  EXPECT_EQ(array_values(xml, "TimeValue"), Tokens{"0.25"});
  EXPECT_EQ(array_values(xml, "connectivity"), (Tokens{"0", "1", "2", "3", "1", "4", "2"}));
  EXPECT_EQ(array_values(xml, "offsets"), (Tokens{"4", "7"}));
  EXPECT_EQ(array_values(xml, "types"), (Tokens{"9", "5"}));
  EXPECT_NE(xml.find("<DataArray type=\"UInt8\" Name=\"types\""), std::string::npos);
  EXPECT_EQ(array_values(xml, "Points"),
            (Tokens{"0", "0", "0", "1", "0", "0", "1", "1", "0", "0", "1", "0", "2", "0.5", "0"}));
  EXPECT_NE(xml.find("Name=\"velocity\" NumberOfComponents=\"3\""), std::string::npos);
  EXPECT_EQ(array_values(xml, "velocity"), (Tokens{"1", "-1", "0", "2", "-2", "0", "3", "-3", "0",
                                                   "4", "-4", "0", "5", "-5", "0"}));
  EXPECT_EQ(array_values(xml, "temperature"), (Tokens{"300", "301", "302", "303", "304"}));
  EXPECT_EQ(array_values(xml, "pressure"), (Tokens{"1.5", "-2"}));
  EXPECT_EQ(array_values(xml, "body"), (Tokens{"0", "1"}));
  EXPECT_NE(xml.find("<DataArray type=\"Int32\" Name=\"body\""), std::string::npos);
  EXPECT_LT(xml.find("<PointData>"), xml.find("<CellData>"));
  EXPECT_LT(xml.find("<CellData>"), xml.find("<Points>"));
  EXPECT_LT(xml.find("<Points>"), xml.find("<Cells>"));
}

TEST(VtuWriter, ExactOutputForOneTriangle) {
  VtuData data;
  data.points.resize(2, 3);
  data.points << 0, 1, 0,  //
      0, 0, 0.1;
  data.tris = {{0, 1, 2}};
  EXPECT_EQ(format_vtu(data),
            "<?xml version=\"1.0\"?>\n"
            "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
            "  <UnstructuredGrid>\n"
            "    <FieldData>\n"
            "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
            "format=\"ascii\">\n"
            "0\n"
            "      </DataArray>\n"
            "    </FieldData>\n"
            "    <Piece NumberOfPoints=\"3\" NumberOfCells=\"1\">\n"
            "      <PointData>\n"
            "      </PointData>\n"
            "      <CellData>\n"
            "      </CellData>\n"
            "      <Points>\n"
            "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" "
            "format=\"ascii\">\n"
            "0 0 0\n1 0 0\n0 0.1 0\n"
            "        </DataArray>\n"
            "      </Points>\n"
            "      <Cells>\n"
            "        <DataArray type=\"Int32\" Name=\"connectivity\" format=\"ascii\">\n"
            "0 1 2\n"
            "        </DataArray>\n"
            "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n"
            "3\n"
            "        </DataArray>\n"
            "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n"
            "5\n"
            "        </DataArray>\n"
            "      </Cells>\n"
            "    </Piece>\n"
            "  </UnstructuredGrid>\n"
            "</VTKFile>\n");
}

TEST(VtuWriter, SizeMismatchesThrow) {
  const auto throws = [](auto change) {
    VtuData data = mixed_mesh();
    change(data);
    EXPECT_THROW(format_vtu(data), std::invalid_argument);
  };
  throws([](VtuData& d) { d.point_scalars[0].second.pop_back(); });
  throws([](VtuData& d) { d.point_vectors[0].second.conservativeResize(2, 4); });
  throws([](VtuData& d) { d.cell_scalars[0].second.push_back(0); });
  throws([](VtuData& d) { d.cell_ints[0].second.pop_back(); });
  throws([](VtuData& d) { d.tris.push_back({0, 1, 2}); });  // cell arrays now one short
  throws([](VtuData& d) { d.quads[0][3] = 5; });            // no point 5
  throws([](VtuData& d) { d.tris[0][0] = -1; });
  throws([](VtuData& d) { d.cell_scalars[0].first = ""; });
  throws([](VtuData& d) { d.point_scalars[0].first = "velocity"; });  // repeated in PointData
  throws([](VtuData& d) { d.cell_ints[0].first = "bad\nname"; });
  throws([](VtuData& d) { d.time = nan_value; });
  try {
    VtuData data = mixed_mesh();
    data.cell_scalars[0].second.push_back(0);
    format_vtu(data);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'pressure' has 3 entries, expected 2"),
              std::string::npos)
        << e.what();
  }
}

TEST(VtuWriter, NonFiniteValuesAndEscapedNames) {
  VtuData data = mixed_mesh();
  data.point_scalars[0].second = {nan_value, inf_value, -inf_value, -nan_value, 5e-324};
  data.cell_scalars[0].first = "a<b & \"c\"";
  const std::string xml = format_vtu(data);
  EXPECT_EQ(xml_error(xml), "");
  EXPECT_EQ(array_values(xml, "temperature"), (Tokens{"nan", "inf", "-inf", "nan", "5e-324"}));
  EXPECT_NE(xml.find("Name=\"a&lt;b &amp; &quot;c&quot;\""), std::string::npos);
}

// ---------------------------------------------------------------- VTU binary encodings
// A decoder written here from the VTK XML file format (not from the writer): it reads each
// DataArray's attributes, finds its bytes (format="appended": at `offset` after the '_' of
// <AppendedData encoding="raw">; format="binary": inline base64) and undoes the UInt64 header
// and the vtkZLibDataCompressor blocks. The arrays it returns are compared bit for bit with the
// values that were written and with the ASCII document of the same data.

struct DecodedArray {
  std::map<std::string, std::string> attributes;
  std::string bytes;  // the data, uncompressed
};

std::string attribute(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const std::size_t at = tag.find(key);
  if (at == std::string::npos) return "";
  const std::size_t begin = at + key.size();
  return tag.substr(begin, tag.find('"', begin) - begin);
}

std::string base64_decode(const std::string& text) {
  auto digit = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  std::string out;
  unsigned buffer = 0;
  int bits = 0;
  for (const char c : text) {
    if (c == '=') break;
    const int d = digit(c);
    if (d < 0) {
      EXPECT_TRUE(std::isspace(static_cast<unsigned char>(c))) << "not base64: '" << c << "'";
      continue;
    }
    buffer = (buffer << 6) | static_cast<unsigned>(d);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out += static_cast<char>((buffer >> bits) & 0xFFu);
    }
  }
  return out;
}

std::uint64_t word(const std::string& bytes, std::size_t at) {
  std::uint64_t w = 0;
  EXPECT_LE(at + 8, bytes.size());
  if (at + 8 <= bytes.size()) std::memcpy(&w, bytes.data() + at, 8);
  return w;
}

// The data of one array from its header and bytes, checking the header's words.
std::string undo_blocks(const std::string& raw, bool compressed, std::size_t* used = nullptr) {
  if (!compressed) {
    const std::uint64_t n = word(raw, 0);
    EXPECT_LE(8 + n, raw.size());
    if (used) *used = 8 + n;
    return raw.substr(8, n);
  }
  const std::uint64_t blocks = word(raw, 0), block = word(raw, 8), last = word(raw, 16);
  EXPECT_EQ(block, 32768u);
  std::size_t at = 8 * (3 + blocks);
  std::string out;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint64_t packed = word(raw, 8 * (3 + b));
    const uLongf expected = b + 1 < blocks || last == 0 ? block : last;
    std::string plain(expected, '\0');
    uLongf got = expected;
    EXPECT_EQ(uncompress(reinterpret_cast<Bytef*>(plain.data()), &got,
                         reinterpret_cast<const Bytef*>(raw.data()) + at, static_cast<uLong>(packed)),
              Z_OK);
    EXPECT_EQ(got, expected) << "block " << b;
    out += plain.substr(0, got);
    at += packed;
  }
  if (used) *used = at;
  return out;
}

// Every DataArray of a VTU document, by Name, decoded.
std::map<std::string, DecodedArray> decode_vtu(const std::string& doc) {
  const std::string open = "<VTKFile ";
  const std::string root = doc.substr(doc.find(open), doc.find('>', doc.find(open)) - doc.find(open));
  const bool compressed = attribute(root, "compressor") == "vtkZLibDataCompressor";
  const bool binary = attribute(root, "version") == "1.0";
  if (binary) {
    EXPECT_EQ(attribute(root, "header_type"), "UInt64");
    EXPECT_EQ(attribute(root, "byte_order"), "LittleEndian");
  }
  std::string appended;
  const std::size_t data_tag = doc.find("<AppendedData encoding=\"raw\">");
  if (data_tag != std::string::npos) {
    const std::size_t start = doc.find('_', data_tag) + 1;
    appended = doc.substr(start, doc.rfind("\n  </AppendedData>") - start);
  }
  const std::size_t piece = doc.find("<Piece ");
  const std::size_t xml_end = data_tag == std::string::npos ? doc.size() : data_tag;
  std::map<std::string, DecodedArray> out;
  for (std::size_t at = doc.find("<DataArray", piece); at < xml_end; at = doc.find("<DataArray", at + 1)) {
    const std::size_t end = doc.find('>', at);
    const std::string tag = doc.substr(at, end - at + 1);
    DecodedArray a;
    for (const char* key : {"type", "Name", "NumberOfComponents", "format", "offset", "ComponentName0",
                            "ComponentName3", "ComponentName5"})
      a.attributes[key] = attribute(tag, key);
    const std::string format = a.attributes["format"];
    if (format == "appended") {
      EXPECT_EQ(tag.substr(tag.size() - 2), "/>");
      const std::size_t offset = std::stoul(a.attributes["offset"]);
      EXPECT_LT(offset, appended.size());
      a.bytes = undo_blocks(appended.substr(offset), compressed);
    } else if (format == "binary") {
      const std::size_t text_end = doc.find("</DataArray>", end);
      const std::string text = doc.substr(end + 1, text_end - end - 1);
      if (!compressed) {
        a.bytes = undo_blocks(base64_decode(text), false);
      } else {
        // The header on its own (3 words, then one per block), then the blocks.
        const std::string first = base64_decode(text.substr(text.find_first_not_of(" \n"), 32));
        const std::uint64_t blocks = word(first, 0);
        std::string trimmed;
        for (const char c : text)
          if (!std::isspace(static_cast<unsigned char>(c))) trimmed += c;
        const std::size_t head_chars = 4 * ((8 * (3 + blocks) + 2) / 3);
        const std::string head = base64_decode(trimmed.substr(0, head_chars));
        EXPECT_EQ(head.size(), 8 * (3 + blocks));
        a.bytes = undo_blocks(head + base64_decode(trimmed.substr(head_chars)), true);
      }
    } else {
      const std::size_t text_end = doc.find("</DataArray>", end);
      a.bytes = doc.substr(end + 1, text_end - end - 1);  // the ascii text itself
    }
    out[a.attributes["Name"]] = a;
  }
  return out;
}

template <class T>
std::vector<T> as(const std::string& bytes) {
  EXPECT_EQ(bytes.size() % sizeof(T), 0u);
  std::vector<T> v(bytes.size() / sizeof(T));
  if (!v.empty()) std::memcpy(v.data(), bytes.data(), v.size() * sizeof(T));
  return v;
}

// The ascii text of an array as doubles (strtod: the shortest round-trip text reads back exactly).
std::vector<double> ascii_values(const std::string& text) {
  std::istringstream in(text);
  std::vector<double> v;
  for (std::string token; in >> token;) v.push_back(std::strtod(token.c_str(), nullptr));
  return v;
}

void expect_bits(const std::vector<double>& got, const std::vector<double>& want, const std::string& what) {
  ASSERT_EQ(got.size(), want.size()) << what;
  for (std::size_t i = 0; i < got.size(); ++i)
    ASSERT_EQ(std::bit_cast<std::uint64_t>(got[i]), std::bit_cast<std::uint64_t>(want[i])) << what << " [" << i << "]";
}

// A grid of nx x ny cells, quads on the left half and triangles on the right, with every kind of
// array; large enough (121 x 41 points: 119 kB of point vectors) for several zlib blocks.
VtuData big_mesh() {
  const int nx = 120, ny = 40, n = (nx + 1) * (ny + 1);
  VtuData d;
  d.points.resize(2, n);
  Eigen::Matrix2Xd velocity(2, n);
  std::vector<double> gap(n);
  std::vector<int> status(n);
  std::mt19937_64 random(42);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const int k = j * (nx + 1) + i;
      d.points(0, k) = 0.01 * i + 1e-7 * uniform(random);
      d.points(1, k) = 0.01 * j;
      velocity(0, k) = uniform(random);
      velocity(1, k) = k < static_cast<int>(awkward.size()) ? awkward[k] : -uniform(random);
      gap[k] = j == 0 ? 0.0 : 1e-3 * j;
      status[k] = j == 0 ? 3 : i == 0 || i == nx || j == ny ? 1 : 0;
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = b + nx + 1, e = a + nx + 1;
      if (i < nx / 2) {
        d.quads.push_back({a, b, c, e});
      } else {
        d.tris.push_back({a, b, c});
        d.tris.push_back({a, c, e});
      }
    }
  const std::size_t cells = d.quads.size() + d.tris.size();
  std::vector<double> vm(cells), tensor(6 * cells);
  std::vector<int> body(cells);
  for (std::size_t c = 0; c < cells; ++c) {
    vm[c] = 1e6 * (1.0 + uniform(random));
    body[c] = c < d.quads.size() ? 0 : 1;
    for (int k = 0; k < 6; ++k) tensor[6 * c + k] = k >= 4 ? 0.0 : 1e5 * uniform(random);
  }
  d.time = 1.0 / 3.0;
  d.point_vectors = {{"displacement", d.points * 1e-3}, {"velocity", velocity}};
  d.point_scalars = {{"contact_gap", gap}};
  d.point_ints = {{"contact_status", status}};
  d.cell_scalars = {{"von_mises", vm}};
  d.cell_tensors = {{"cauchy_stress", tensor}};
  d.cell_ints = {{"body", body}};
  return d;
}

std::vector<double> xy0_values(const Eigen::Matrix2Xd& m) {
  std::vector<double> v;
  for (Eigen::Index j = 0; j < m.cols(); ++j) v.insert(v.end(), {m(0, j), m(1, j), 0.0});
  return v;
}

TEST(VtuWriter, BinaryEncodingsRoundTripBitForBit) {
  const VtuData data = big_mesh();
  const std::map<std::string, DecodedArray> text = decode_vtu(format_vtu(data));
  std::vector<std::int32_t> connectivity;
  for (const auto& q : data.quads) connectivity.insert(connectivity.end(), q.begin(), q.end());
  for (const auto& t : data.tris) connectivity.insert(connectivity.end(), t.begin(), t.end());
  const std::size_t cells = data.quads.size() + data.tris.size();
  ASSERT_GT(xy0_values(data.points).size() * 8, 3 * kVtuZlibBlock) << "several zlib blocks";

  struct Case {
    VtuFormat format;
    const char* attribute;
  };
  std::map<std::string, std::size_t> sizes;
  for (const Case& c : {Case{{VtuEncoding::binary, VtuCompression::none}, "appended"},
                        Case{{VtuEncoding::binary, VtuCompression::zlib}, "appended"},
                        Case{{VtuEncoding::base64, VtuCompression::none}, "binary"},
                        Case{{VtuEncoding::base64, VtuCompression::zlib}, "binary"}}) {
    const std::string doc = format_vtu(data, c.format);
    const std::string what = std::string(c.format.encoding == VtuEncoding::binary ? "binary" : "base64") +
                             (c.format.compression == VtuCompression::zlib ? "+zlib" : "");
    sizes[what] = doc.size();
    SCOPED_TRACE(what);
    // The XML around the data is well-formed (raw appended bytes are not XML: checked up to them).
    const std::size_t raw = doc.find("<AppendedData");
    EXPECT_EQ(xml_error(raw == std::string::npos ? doc : doc.substr(0, raw) + "</VTKFile>\n"), "");
    EXPECT_EQ(doc.find("compressor=") != std::string::npos, c.format.compression == VtuCompression::zlib);
    const std::map<std::string, DecodedArray> a = decode_vtu(doc);
    ASSERT_EQ(a.size(), text.size());
    for (const auto& [name, array] : a) {
      EXPECT_EQ(array.attributes.at("format"), c.attribute) << name;
      EXPECT_EQ(array.attributes.at("type"), text.at(name).attributes.at("type")) << name;
      EXPECT_EQ(array.attributes.at("NumberOfComponents"), text.at(name).attributes.at("NumberOfComponents")) << name;
    }
    // Against the values written, bit for bit, and against the ascii document of the same data.
    for (const auto& [name, values] : data.point_vectors) {
      expect_bits(as<double>(a.at(name).bytes), xy0_values(values), name);
      expect_bits(as<double>(a.at(name).bytes), ascii_values(text.at(name).bytes), name + " (ascii)");
    }
    expect_bits(as<double>(a.at("Points").bytes), xy0_values(data.points), "Points");
    expect_bits(as<double>(a.at("contact_gap").bytes), data.point_scalars[0].second, "contact_gap");
    expect_bits(as<double>(a.at("von_mises").bytes), data.cell_scalars[0].second, "von_mises");
    expect_bits(as<double>(a.at("von_mises").bytes), ascii_values(text.at("von_mises").bytes), "von_mises (ascii)");
    expect_bits(as<double>(a.at("cauchy_stress").bytes), data.cell_tensors[0].second, "cauchy_stress");
    expect_bits(as<double>(a.at("cauchy_stress").bytes), ascii_values(text.at("cauchy_stress").bytes),
                "cauchy_stress (ascii)");
    EXPECT_EQ(a.at("cauchy_stress").attributes.at("ComponentName0"), "XX");
    EXPECT_EQ(a.at("cauchy_stress").attributes.at("ComponentName3"), "XY");
    EXPECT_EQ(a.at("cauchy_stress").attributes.at("ComponentName5"), "XZ");
    EXPECT_EQ(as<std::int32_t>(a.at("contact_status").bytes), data.point_ints[0].second);
    EXPECT_EQ(as<std::int32_t>(a.at("body").bytes), data.cell_ints[0].second);
    EXPECT_EQ(as<std::int32_t>(a.at("connectivity").bytes), connectivity);
    const std::vector<std::int64_t> offsets = as<std::int64_t>(a.at("offsets").bytes);
    const std::vector<std::uint8_t> types = as<std::uint8_t>(a.at("types").bytes);
    ASSERT_EQ(offsets.size(), cells);
    ASSERT_EQ(types.size(), cells);
    EXPECT_EQ(offsets.back(), static_cast<std::int64_t>(connectivity.size()));
    EXPECT_EQ(offsets[0], 4);
    EXPECT_EQ(types.front(), 9);
    EXPECT_EQ(types.back(), 5);
    // The time stays inline ascii in every encoding.
    EXPECT_NE(doc.find("Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">\n0.3333333333333333\n"),
              std::string::npos);
  }
  // Sizes: raw bytes are 3/4 of their base64 text; compression pays on these arrays.
  EXPECT_LT(sizes.at("binary"), sizes.at("base64"));
  EXPECT_LT(sizes.at("binary+zlib"), sizes.at("binary"));
  EXPECT_LT(sizes.at("base64+zlib"), sizes.at("base64"));
}

// Non-finite values, which the ascii format cannot carry to VTK, keep their bits in binary.
TEST(VtuWriter, BinaryKeepsNonFiniteBits) {
  VtuData data = mixed_mesh();
  data.point_scalars[0].second = {nan_value, inf_value, -inf_value, -nan_value, 5e-324};
  for (const VtuEncoding e : {VtuEncoding::binary, VtuEncoding::base64})
    for (const VtuCompression z : {VtuCompression::none, VtuCompression::zlib}) {
      const auto a = decode_vtu(format_vtu(data, {e, z}));
      expect_bits(as<double>(a.at("temperature").bytes), data.point_scalars[0].second, "temperature");
    }
}

TEST(VtuWriter, AsciiWithCompressionThrows) {
  EXPECT_THROW(format_vtu(mixed_mesh(), {VtuEncoding::ascii, VtuCompression::zlib}), std::invalid_argument);
  VtuData data = mixed_mesh();
  data.cell_tensors = {{"strain", std::vector<double>(6 * 2 - 1, 0.0)}};  // one short of 6 per cell
  EXPECT_THROW(format_vtu(data, {VtuEncoding::binary, VtuCompression::zlib}), std::invalid_argument);
}

TEST(PvdWriter, ExactOutputAndChecks) {
  const std::string pvd = format_pvd({{0.0, "out/s_0.vtu"}, {1e-5, "out/s&1.vtu"}});
  EXPECT_EQ(pvd,
            "<?xml version=\"1.0\"?>\n"
            "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
            "  <Collection>\n"
            "    <DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"out/s_0.vtu\"/>\n"
            "    <DataSet timestep=\"1e-05\" group=\"\" part=\"0\" file=\"out/s&amp;1.vtu\"/>\n"
            "  </Collection>\n"
            "</VTKFile>\n");
  EXPECT_EQ(xml_error(pvd), "");
  EXPECT_EQ(xml_error(format_pvd({})), "");
  // A step's time n dt is labelled as written, not with its last-bit noise.
  const double t = 300 * 1e-5;  // 0.0030000000000000005
  EXPECT_NE(format_pvd({{t, "a.vtu"}}).find("timestep=\"0.003\""), std::string::npos);
  EXPECT_NE(format_pvd({{2.5e-7 * 12345, "a.vtu"}}).find("timestep=\"0.00308625\""), std::string::npos);
  EXPECT_THROW(format_pvd({{nan_value, "a.vtu"}}), std::invalid_argument);
  EXPECT_THROW(format_pvd({{0.0, ""}}), std::invalid_argument);
}

// ---------------------------------------------------------------- VTU of 3D meshes
// The same writer on a VtuData3 (hexahedra and tetrahedra): the ascii document parsed back here,
// and the binary encodings decoded by decode_vtu above, against the mesh's own arrays.

// A box of nx x ny x nz hexahedra, followed by the 6 tetrahedra of each of its first
// `tet_cells` cells (overlapping: the writer does not care), with every kind of array.
VtuData3 box_data(int nx, int ny, int nz, int tet_cells) {
  const Mesh3 hexes = make_box({.size = Vec3(0.3, 0.2, 0.1), .nx = nx, .ny = ny, .nz = nz, .origin = Vec3(-0.1, 0.05, 1.0 / 3.0)});
  const Mesh3 tets = make_box({.size = Vec3(0.3, 0.2, 0.1), .nx = nx, .ny = ny, .nz = nz, .origin = Vec3(-0.1, 0.05, 1.0 / 3.0),
                               .tetrahedra = true});
  VtuData3 d;
  d.points = hexes.nodes;
  d.hexes = hexes.hexes;
  d.tets.assign(tets.tets.begin(), tets.tets.begin() + 6 * tet_cells);
  const Eigen::Index n = d.points.cols();
  const std::size_t cells = d.hexes.size() + d.tets.size();
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::Matrix3Xd displacement(3, n), velocity(3, n);
  for (Eigen::Index j = 0; j < n; ++j)
    for (int i = 0; i < 3; ++i) {
      displacement(i, j) = 1e-3 * uniform(random);
      velocity(i, j) = j < static_cast<Eigen::Index>(awkward.size()) && i == 2 ? awkward[j] : uniform(random);
    }
  std::vector<double> gap(n), vm(cells), stress(6 * cells);
  std::vector<int> status(n), body(cells);
  for (Eigen::Index j = 0; j < n; ++j) {
    gap[j] = uniform(random);
    status[j] = static_cast<int>(j % 3);
  }
  for (std::size_t c = 0; c < cells; ++c) {
    vm[c] = 1e6 * (1.0 + uniform(random));
    body[c] = c < d.hexes.size() ? 0 : 1;
    for (int k = 0; k < 6; ++k) stress[6 * c + k] = 1e5 * uniform(random);
  }
  d.time = 0.125;
  d.point_vectors = {{"displacement", displacement}, {"velocity", velocity}};
  d.point_scalars = {{"contact_gap", gap}};
  d.point_ints = {{"contact_status", status}};
  d.cell_scalars = {{"von_mises", vm}};
  d.cell_tensors = {{"cauchy_stress", stress}};
  d.cell_ints = {{"body", body}};
  return d;
}

std::vector<double> flat(const Eigen::Matrix3Xd& m) { return {m.data(), m.data() + m.size()}; }

std::vector<std::int32_t> connectivity_of(const VtuData3& d) {
  std::vector<std::int32_t> c;
  for (const auto& h : d.hexes) c.insert(c.end(), h.begin(), h.end());
  for (const auto& t : d.tets) c.insert(c.end(), t.begin(), t.end());
  return c;
}

TEST(VtuWriter3d, AsciiRoundTripOfCoordinatesAndConnectivity) {
  const VtuData3 data = box_data(3, 2, 2, 2);
  const std::string xml = format_vtu(data);
  EXPECT_EQ(xml_error(xml), "");
  EXPECT_NE(xml.find("<Piece NumberOfPoints=\"36\" NumberOfCells=\"24\">"), std::string::npos);  // 12 + 12
  // Coordinates and vectors read back bit for bit, three per point.
  expect_bits(ascii_values(decode_vtu(xml).at("Points").bytes), flat(data.points), "Points");
  expect_bits(ascii_values(decode_vtu(xml).at("displacement").bytes), flat(data.point_vectors[0].second), "displacement");
  expect_bits(ascii_values(decode_vtu(xml).at("velocity").bytes), flat(data.point_vectors[1].second), "velocity");
  EXPECT_NE(xml.find("Name=\"velocity\" NumberOfComponents=\"3\""), std::string::npos);
  // Connectivity one cell per line: 8 indices for a hexahedron, 4 for a tetrahedron.
  const std::string text = decode_vtu(xml).at("connectivity").bytes;
  std::istringstream lines(text.substr(text.find('\n') + 1));
  std::vector<std::int32_t> connectivity;
  std::size_t cell = 0;
  // (The text ends with the indentation of </DataArray>, a line of blanks.)
  for (std::string line; std::getline(lines, line) && line.find_first_not_of(' ') != std::string::npos; ++cell) {
    std::istringstream in(line);
    std::size_t count = 0;
    for (std::int32_t v; in >> v; ++count) connectivity.push_back(v);
    EXPECT_EQ(count, cell < data.hexes.size() ? 8u : 4u) << "cell " << cell;
  }
  EXPECT_EQ(cell, 24u);
  EXPECT_EQ(connectivity, connectivity_of(data));
  Tokens offsets, types;
  for (std::size_t c = 0; c < 24; ++c) {
    offsets.push_back(std::to_string(c < 12 ? 8 * (c + 1) : 96 + 4 * (c - 11)));
    types.push_back(c < 12 ? "12" : "10");
  }
  EXPECT_EQ(array_values(xml, "offsets"), offsets);
  EXPECT_EQ(array_values(xml, "types"), types);
  EXPECT_EQ(array_values(xml, "body").size(), 24u);
  EXPECT_EQ(array_values(xml, "cauchy_stress").size(), 6u * 24u);
  EXPECT_EQ(array_values(xml, "contact_status").size(), 36u);
  EXPECT_EQ(array_values(xml, "TimeValue"), Tokens{"0.125"});
}

TEST(VtuWriter3d, BinaryAndZlibEncodingsHoldTheAsciiArrays) {
  const VtuData3 data = box_data(20, 20, 20, 40);  // 9261 points: 222 kB of coordinates
  ASSERT_GT(flat(data.points).size() * 8, 3 * kVtuZlibBlock) << "several zlib blocks";
  const std::map<std::string, DecodedArray> text = decode_vtu(format_vtu(data));
  const std::vector<std::int32_t> connectivity = connectivity_of(data);
  const std::size_t cells = data.hexes.size() + data.tets.size();
  for (const VtuEncoding e : {VtuEncoding::binary, VtuEncoding::base64})
    for (const VtuCompression z : {VtuCompression::none, VtuCompression::zlib}) {
      SCOPED_TRACE(std::string(e == VtuEncoding::binary ? "binary" : "base64") + (z == VtuCompression::zlib ? "+zlib" : ""));
      const std::string doc = format_vtu(data, {e, z});
      const std::map<std::string, DecodedArray> a = decode_vtu(doc);
      ASSERT_EQ(a.size(), text.size());
      for (const auto& [name, array] : a) {
        EXPECT_EQ(array.attributes.at("type"), text.at(name).attributes.at("type")) << name;
        EXPECT_EQ(array.attributes.at("NumberOfComponents"), text.at(name).attributes.at("NumberOfComponents")) << name;
      }
      for (const char* name : {"Points", "displacement", "velocity", "contact_gap", "von_mises", "cauchy_stress"})
        expect_bits(as<double>(a.at(name).bytes), ascii_values(text.at(name).bytes), name);
      expect_bits(as<double>(a.at("Points").bytes), flat(data.points), "Points");
      expect_bits(as<double>(a.at("velocity").bytes), flat(data.point_vectors[1].second), "velocity");
      EXPECT_EQ(as<std::int32_t>(a.at("connectivity").bytes), connectivity);
      EXPECT_EQ(as<std::int32_t>(a.at("contact_status").bytes), data.point_ints[0].second);
      EXPECT_EQ(as<std::int32_t>(a.at("body").bytes), data.cell_ints[0].second);
      const std::vector<std::int64_t> offsets = as<std::int64_t>(a.at("offsets").bytes);
      const std::vector<std::uint8_t> types = as<std::uint8_t>(a.at("types").bytes);
      ASSERT_EQ(offsets.size(), cells);
      ASSERT_EQ(types.size(), cells);
      for (std::size_t c = 0; c < cells; ++c) {
        const bool hex = c < data.hexes.size();
        EXPECT_EQ(offsets[c], hex ? 8 * static_cast<std::int64_t>(c + 1)
                                  : 8 * static_cast<std::int64_t>(data.hexes.size()) + 4 * static_cast<std::int64_t>(c + 1 - data.hexes.size()));
        EXPECT_EQ(types[c], hex ? 12 : 10);
      }
      EXPECT_EQ(offsets.back(), static_cast<std::int64_t>(connectivity.size()));
    }
}

TEST(VtuWriter3d, SizeMismatchesAndBadIndicesThrow) {
  const auto message = [](auto change) -> std::string {
    VtuData3 data = box_data(2, 1, 1, 1);
    change(data);
    try {
      format_vtu(data);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "no exception";
  };
  EXPECT_EQ(message([](VtuData3&) {}), "no exception");
  EXPECT_EQ(message([](VtuData3& d) { d.hexes[1][7] = 12; }),
            "format_vtu: hexahedron 1 refers to point 12 but there are 12 points");
  EXPECT_EQ(message([](VtuData3& d) { d.tets[5][0] = -1; }),
            "format_vtu: tetrahedron 5 refers to point -1 but there are 12 points");
  EXPECT_EQ(message([](VtuData3& d) { d.point_vectors[0].second.conservativeResize(3, 11); }),
            "format_vtu: PointData array 'displacement' has 11 entries, expected 12");
  EXPECT_EQ(message([](VtuData3& d) { d.tets.pop_back(); }),  // cell arrays now one too long
            "format_vtu: CellData array 'von_mises' has 8 entries, expected 7");
  EXPECT_EQ(message([](VtuData3& d) { d.cell_tensors[0].second.pop_back(); }),
            "format_vtu: CellData array 'cauchy_stress' has 47 entries, expected 48");
  EXPECT_EQ(message([](VtuData3& d) { d.time = inf_value; }), "format_vtu: time is not finite");
  EXPECT_THROW(format_vtu(box_data(1, 1, 1, 0), {VtuEncoding::ascii, VtuCompression::zlib}), std::invalid_argument);
}

// ---------------------------------------------------------------- atomic file

class AtomicFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ricochet::test_support::fresh_test_dir("ricochet_atomic_");
  }
  void TearDown() override {
    std::error_code ignored;
    fs::permissions(dir_ / "ro", fs::perms::owner_all, ignored);
    fs::remove_all(dir_, ignored);
  }
  // Every path under the test directory, relative to it.
  std::set<std::string> entries() const {
    std::set<std::string> out;
    for (const auto& entry : fs::recursive_directory_iterator(dir_)) {
      out.insert(fs::relative(entry.path(), dir_).generic_string());
    }
    return out;
  }
  static std::string read(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  fs::path dir_;
};

TEST_F(AtomicFile, WritesCreatesParentsAndLeavesNoTemporary) {
  const fs::path target = dir_ / "a" / "b" / "summary.json";
  const std::string content("binary\0 and\nlines\n", 18);
  write_file_atomic(target, content);
  EXPECT_EQ(read(target), content);
  EXPECT_EQ(entries(), (std::set<std::string>{"a", "a/b", "a/b/summary.json"}));
  write_file_atomic(target, "short");  // replaces an existing file
  EXPECT_EQ(read(target), "short");
  write_file_atomic(target, "");
  EXPECT_EQ(read(target), "");
  EXPECT_EQ(entries(), (std::set<std::string>{"a", "a/b", "a/b/summary.json"}));
}

TEST_F(AtomicFile, PathUnderRegularFileThrowsAndLeavesNothing) {
  write_file_atomic(dir_ / "blocker", "keep");
  for (const fs::path& target : {dir_ / "blocker" / "out.json", dir_ / "blocker" / "sub" / "x"}) {
    try {
      write_file_atomic(target, "data");
      ADD_FAILURE() << "no exception for " << target;
    } catch (const std::runtime_error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(target.string()), std::string::npos) << message;
      EXPECT_NE(message.find("Not a directory"), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    }
  }
  EXPECT_EQ(entries(), std::set<std::string>{"blocker"});
  EXPECT_EQ(read(dir_ / "blocker"), "keep");
}

TEST_F(AtomicFile, FailedRenameRemovesTemporary) {
  fs::create_directories(dir_ / "out.json" / "inside");  // a directory where the file should go
  EXPECT_THROW(write_file_atomic(dir_ / "out.json", "data"), std::runtime_error);
  EXPECT_EQ(entries(), (std::set<std::string>{"out.json", "out.json/inside"}));
  EXPECT_THROW(write_file_atomic(dir_ / "dir" / "", "data"), std::runtime_error);
}

}  // namespace
}  // namespace ricochet
