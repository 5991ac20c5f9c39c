// SPDX-License-Identifier: Apache-2.0
#include "io/pcd_header.h"

#include <array>
#include <charconv>
#include <optional>
#include <sstream>

#include "io/pcd_io.h"

namespace rsu::io {
namespace {

constexpr std::array<std::string_view, 10> kKeywords = {"VERSION", "FIELDS", "SIZE",      "TYPE",   "COUNT",
                                                        "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
enum Keyword : std::size_t {
  kVersion,
  kFields,
  kSize,
  kType,
  kCount,
  kWidth,
  kHeight,
  kViewpoint,
  kPoints,
  kData
};
constexpr std::string_view kSpace = " \t\n\v\f\r";
constexpr std::uint32_t kMaxCount = 1U << 16;
constexpr std::uint64_t kMaxPointStep = 1U << 20;

[[noreturn]] void malformed(const std::string& what) {
  throw PcdError("malformed PCD header: " + what);
}

std::vector<std::string_view> words_of(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t begin = line.find_first_not_of(kSpace);
  while (begin != std::string_view::npos) {
    const std::size_t end = std::min(line.find_first_of(kSpace, begin), line.size());
    words.push_back(line.substr(begin, end - begin));
    begin = line.find_first_not_of(kSpace, end);
  }
  return words;
}

// A plain decimal count below 2^31.
std::uint64_t count_of(std::string_view word, std::string_view keyword) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
  if (ec != std::errc() || end != word.data() + word.size() || v >= (std::uint64_t{1} << 31))
    malformed(std::string(keyword) + ": \"" + std::string(word) + "\" is not a count");
  return v;
}

// One value per field after the keyword.
void expect_per_field(const std::vector<std::string_view>& words, const PcdHeader& h,
                      std::string_view keyword) {
  if (h.fields.empty() || words.size() - 1 != h.fields.size())
    malformed(std::string(keyword) + " does not match FIELDS");
}

void set_values(PcdHeader& h, Keyword key, const std::vector<std::string_view>& words) {
  const std::string_view name = kKeywords[key];
  switch (key) {
    case kFields:
      for (std::size_t i = 1; i < words.size(); ++i)
        h.fields.push_back({.name = std::string(words[i])});
      return;
    case kSize:
    case kCount:
      expect_per_field(words, h, name);
      for (std::size_t i = 0; i < h.fields.size(); ++i)
        (key == kSize ? h.fields[i].size : h.fields[i].count) =
            static_cast<std::uint32_t>(count_of(words[i + 1], name));
      return;
    case kType:
      expect_per_field(words, h, name);
      for (std::size_t i = 0; i < h.fields.size(); ++i) {
        if (words[i + 1].size() != 1)
          malformed("TYPE \"" + std::string(words[i + 1]) + "\"");
        h.fields[i].type = words[i + 1][0];
      }
      return;
    case kWidth:
    case kHeight:
    case kPoints:
      if (words.size() != 2)
        malformed(std::string(name) + " needs one value");
      (key == kWidth ? h.width : key == kHeight ? h.height : h.points) = count_of(words[1], name);
      return;
    case kData:
      if (words.size() != 2 ||
          (words[1] != "ascii" && words[1] != "binary" && words[1] != "binary_compressed"))
        malformed("DATA must be ascii, binary or binary_compressed");
      h.data = words[1] == "ascii"    ? PcdData::ascii
               : words[1] == "binary" ? PcdData::binary
                                      : PcdData::binary_compressed;
      return;
    case kVersion:
    case kViewpoint:
      return;  // nothing the points depend on
  }
}

// The fields' sizes, types and counts make sense; offsets and the point step follow from them.
void lay_out(PcdHeader& h) {
  std::uint64_t offset = 0;
  for (PcdField& f : h.fields) {
    const bool size_ok = f.size == 1 || f.size == 2 || f.size == 4 || f.size == 8;
    const bool type_ok = f.type == 'I' || f.type == 'U' || (f.type == 'F' && (f.size == 4 || f.size == 8));
    if (!size_ok || !type_ok)
      malformed("field \"" + f.name + "\": unsupported SIZE " + std::to_string(f.size) + " TYPE " + f.type);
    if (f.count == 0 || f.count > kMaxCount)
      malformed("field \"" + f.name + "\": COUNT " + std::to_string(f.count));
    f.offset = static_cast<std::uint32_t>(offset);
    offset += std::uint64_t{f.size} * f.count;
    if (offset > kMaxPointStep)
      malformed("SIZE x COUNT: points larger than 1 MiB");
  }
  h.point_step = static_cast<std::uint32_t>(offset);
}

}  // namespace

const PcdField* PcdHeader::find(std::string_view name) const {
  for (const PcdField& f : fields) {
    if (f.name == name)
      return &f;
  }
  return nullptr;
}

PcdHeader parse_pcd_header(std::string_view file) {
  PcdHeader h;
  std::array<bool, kKeywords.size()> seen{};
  std::size_t next = 0;  // the first keyword still allowed
  std::size_t pos = 0;
  while (!seen[kData]) {
    if (pos >= file.size())
      malformed("no DATA line");
    const std::size_t eol = std::min(file.find('\n', pos), file.size());
    const std::vector<std::string_view> words = words_of(file.substr(pos, eol - pos));
    pos = eol + 1;
    if (words.empty() || words[0].front() == '#')
      continue;
    std::size_t key = 0;
    while (key < kKeywords.size() && words[0] != kKeywords[key])
      ++key;
    if (key == kKeywords.size())
      malformed("unknown line \"" + std::string(words[0]) + "\"");
    if (key < next)
      malformed(std::string(kKeywords[key]) + " repeated or out of order");
    next = key + 1;
    seen[key] = true;
    set_values(h, static_cast<Keyword>(key), words);
  }
  for (const Keyword required : {kFields, kSize, kType, kPoints})
    if (!seen[required])
      malformed(std::string("no ") + std::string(kKeywords[required]) + " line");
  if (h.fields.empty())
    malformed("no fields");
  if (!seen[kWidth])
    h.width = h.points;
  if (h.width * h.height != h.points)
    malformed("WIDTH x HEIGHT is not POINTS");
  lay_out(h);
  h.data_offset = std::min(pos, file.size());
  return h;
}

std::string pcd_header_text(const std::vector<PcdField>& fields, std::size_t points) {
  std::ostringstream out;
  out << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7";
  auto line = [&](const char* keyword, auto value_of) {
    out << '\n' << keyword;
    for (const PcdField& f : fields)
      out << ' ' << value_of(f);
  };
  line("FIELDS", [](const PcdField& f) { return f.name; });
  line("SIZE", [](const PcdField& f) { return f.size; });
  line("TYPE", [](const PcdField& f) { return f.type; });
  line("COUNT", [](const PcdField& f) { return f.count; });
  out << "\nWIDTH " << points << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << points
      << "\nDATA binary\n";
  return out.str();
}

}  // namespace rsu::io
