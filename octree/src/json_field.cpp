#include "nestlight/octree/json_field.h"

#include <algorithm>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

#include "nestlight/octree/error.h"

namespace nestlight {

using nlohmann::json;

void JsonField::fail(const std::string& why) const {
  throw Error(file_, path_, why);
}

JsonField JsonField::at(const std::string& key) const {
  if (!j_->is_object()) fail("expected an object, got " + std::string(j_->type_name()));
  auto it = j_->find(key);
  if (it == j_->end()) fail("missing \"" + key + "\"");
  return JsonField(*it, path_.empty() ? key : path_ + "." + key, file_);
}

JsonField JsonField::at(size_t i) const {
  if (!j_->is_array() || i >= j_->size())
    fail("expected an array of at least " + std::to_string(i + 1) + " values");
  return JsonField((*j_)[i], path_ + "[" + std::to_string(i) + "]", file_);
}

void JsonField::expectObject(std::initializer_list<const char*> allowed) const {
  expectObject(std::vector<std::string>(allowed.begin(), allowed.end()));
}

void JsonField::expectObject(const std::vector<std::string>& allowed) const {
  if (!j_->is_object()) fail("expected an object, got " + std::string(j_->type_name()));
  const std::set<std::string> ok(allowed.begin(), allowed.end());
  for (auto it = j_->begin(); it != j_->end(); ++it) {
    if (ok.count(it.key())) continue;
    std::string list;
    for (const auto& k : ok) list += (list.empty() ? "" : ", ") + k;
    JsonField(it.value(), path_.empty() ? it.key() : path_ + "." + it.key(), file_)
        .fail("unknown field (expected one of: " + list + ")");
  }
}

size_t JsonField::arraySize() const {
  if (!j_->is_array()) fail("expected an array, got " + std::string(j_->type_name()));
  return j_->size();
}

double JsonField::number(double lo, double hi) const {
  if (!j_->is_number()) fail("expected a number, got " + std::string(j_->type_name()));
  const double v = j_->get<double>();
  if (!std::isfinite(v) || v < lo || v > hi) {
    std::ostringstream s;
    s << "expected a number in [" << lo << ", " << hi << "], got " << v;
    fail(s.str());
  }
  return v;
}

int64_t JsonField::integer(int64_t lo, int64_t hi) const {
  if (!j_->is_number_integer() && !j_->is_number_unsigned())
    fail("expected an integer, got " + std::string(j_->type_name()) + " " + j_->dump());
  if (j_->is_number_unsigned() && j_->get<uint64_t>() > uint64_t(INT64_MAX))
    fail("expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
         j_->dump());
  const int64_t v = j_->get<int64_t>();
  if (v < lo || v > hi)
    fail("expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
         std::to_string(v));
  return v;
}

uint64_t JsonField::count() const {
  if (j_->is_number_unsigned()) return j_->get<uint64_t>();
  if (j_->is_number_integer() && j_->get<int64_t>() >= 0) return uint64_t(j_->get<int64_t>());
  fail("expected a non-negative integer, got " + j_->dump());
}

bool JsonField::boolean() const {
  if (!j_->is_boolean()) fail("expected true or false, got " + std::string(j_->type_name()));
  return j_->get<bool>();
}

std::string JsonField::string() const {
  if (!j_->is_string()) fail("expected a string, got " + std::string(j_->type_name()));
  return j_->get<std::string>();
}

std::string JsonField::choice(std::initializer_list<const char*> options) const {
  return choice(std::vector<std::string>(options.begin(), options.end()));
}

std::string JsonField::choice(const std::vector<std::string>& options) const {
  const std::string v = string();
  std::string list;
  for (const auto& o : options) {
    if (v == o) return v;
    list += (list.empty() ? "" : ", ") + o;
  }
  fail("'" + v + "' is not one of: " + list);
}

std::array<double, 3> JsonField::vec3(double lo, double hi) const {
  if (!j_->is_array() || j_->size() != 3) fail("expected an array of 3 numbers, got " + j_->dump());
  return {at(size_t(0)).number(lo, hi), at(size_t(1)).number(lo, hi), at(size_t(2)).number(lo, hi)};
}

json readJsonFile(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw Error(file.string(), "", "cannot open");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    throw Error(file.string(), Error::atByte(e.byte), std::string("invalid JSON: ") + e.what());
  } catch (const json::out_of_range& e) {
    // A number beyond a double (1e400): the parser names the literal but neither its place nor
    // its field, so both are found here.
    const std::string what = e.what();
    const size_t q0 = what.find('\''), q1 = q0 == std::string::npos ? q0 : what.find('\'', q0 + 1);
    const std::string literal =
        q1 == std::string::npos ? std::string() : what.substr(q0 + 1, q1 - q0 - 1);
    const size_t at = literal.empty() ? std::string::npos : text.find(literal);
    if (at == std::string::npos) throw Error(file.string(), "", "invalid JSON: " + what);
    const uint64_t line = 1 + uint64_t(std::count(text.begin(), text.begin() + long(at), '\n'));
    std::string field;
    const size_t colon = text.find_last_not_of(" \t\r\n", at == 0 ? 0 : at - 1);
    if (colon != std::string::npos && text[colon] == ':') {
      const size_t close = text.find_last_not_of(" \t\r\n", colon == 0 ? 0 : colon - 1);
      const size_t open =
          close == std::string::npos || close == 0 ? std::string::npos : text.rfind('"', close - 1);
      if (open != std::string::npos && text[close] == '"')
        field = "field \"" + text.substr(open + 1, close - open - 1) + "\": ";
    }
    throw Error(
        file.string(), Error::atLine(line),
        field + "the number " + literal + " is beyond the range of a double (about 1.8e308)");
  }
}

}  // namespace nestlight
