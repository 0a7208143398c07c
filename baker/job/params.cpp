#include "job/params.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "core/error.hpp"

namespace hfbake {

namespace {

std::string number_text(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

}  // namespace

std::string quoted_list(const std::vector<std::string>& names) {
  std::string list;
  for (std::size_t k = 0; k < names.size(); ++k) {
    if (k > 0) list += k + 1 == names.size() ? (names.size() > 2 ? ", or " : " or ") : ", ";
    list += "\"" + names[k] + "\"";
  }
  return list;
}

Params::Params(const nlohmann::json& object, std::string file, std::string pointer)
    : object_(object), file_(std::move(file)), pointer_(std::move(pointer)) {}

void Params::fail(const std::string& key, const std::string& what) const {
  throw InputError(file_, key.empty() ? pointer_ : pointer_ + "/" + key, what);
}

int Params::integer(const char* key, int fallback, int lo, int hi) {
  int x = fallback;
  if (has(key)) {
    const auto& v = raw(key);
    if (!v.is_number_integer()) fail(key, "must be an integer");
    const long long y = v.is_number_unsigned() && v.get<unsigned long long>() > (1ull << 62)
                            ? (1ll << 62)
                            : v.get<long long>();
    if (y < lo || y > hi)
      fail(key, "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    x = int(y);
  }
  resolved_[key] = x;
  return x;
}

double Params::number(const char* key, double fallback, double lo, double hi) {
  double x = fallback;
  if (has(key)) {
    const auto& v = raw(key);
    if (!v.is_number()) fail(key, "must be a number");
    x = v.get<double>();
    if (!std::isfinite(x) || !(x >= lo && x <= hi))
      fail(key, "must be a number in [" + number_text(lo) + ", " + number_text(hi) + "]");
  }
  resolved_[key] = x;
  return x;
}

bool Params::object(const char* key, const std::function<void(Params&)>& read) {
  if (!has(key)) return false;
  if (!raw(key).is_object()) fail(key, "must be an object");
  Params inner(raw(key), file_, pointer_ + "/" + key);
  read(inner);
  resolved_[key] = inner.resolved_;
  return true;
}

bool Params::boolean(const char* key, bool fallback) {
  bool x = fallback;
  if (has(key)) {
    if (!raw(key).is_boolean()) fail(key, "must be true or false");
    x = raw(key).get<bool>();
  }
  resolved_[key] = x;
  return x;
}

std::string Params::choice(const char* key, const std::string& fallback,
                           std::initializer_list<const char*> allowed) {
  std::string x = fallback;
  if (has(key)) {
    const auto& v = raw(key);
    const std::string s = v.is_string() ? v.get<std::string>() : "";
    const bool ok =
        v.is_string() && std::any_of(allowed.begin(), allowed.end(), [&](const char* a) { return s == a; });
    if (!ok)
      fail(key, "must be one of " + quoted_list(std::vector<std::string>(allowed.begin(), allowed.end())));
    x = s;
  }
  resolved_[key] = x;
  return x;
}

std::optional<std::string> Params::text(const char* key, std::size_t max_length) {
  if (!has(key)) return std::nullopt;
  const auto& v = raw(key);
  if (!v.is_string() || v.get_ref<const std::string&>().size() > max_length)
    fail(key, "must be a string of at most " + std::to_string(max_length) + " characters");
  std::string s = v.get<std::string>();
  resolved_[key] = s;
  return s;
}

std::vector<std::string> Params::layers(const std::vector<std::string>& known,
                                        const std::vector<std::string>& defaults) {
  std::vector<std::string> out = defaults;
  if (has("layers")) {
    const auto& v = raw("layers");
    if (!v.is_array()) fail("layers", "must be an array of layer names");
    out.clear();
    std::set<std::string> seen;
    for (std::size_t k = 0; k < v.size(); ++k) {
      const std::string name = v[k].is_string() ? v[k].get<std::string>() : v[k].dump();
      const std::string where = "layers/" + std::to_string(k);
      if (std::find(known.begin(), known.end(), name) == known.end())
        fail(where,
             "layer \"" + name + "\" is not written by this method (it writes " + quoted_list(known) + ")");
      if (!seen.insert(name).second) fail(where, "layer \"" + name + "\" is named twice");
      out.push_back(name);
    }
    if (out.empty()) fail("layers", "must name at least one layer");
  }
  resolved_["layers"] = out;
  layers_ = out;
  return out;
}

double Params::number_that(const char* key, bool (*ok)(double), const std::string& what) {
  const auto& v = raw(key);
  if (!v.is_number() || !ok(v.get<double>())) fail(key, what);
  const double x = v.get<double>();
  resolved_[key] = x;
  return x;
}

std::optional<double> Params::word_or_number(const char* key, const char* word, double lo, double hi,
                                             const std::string& what) const {
  const auto& v = raw(key);
  if (v.is_string() && v.get<std::string>() == word) return std::nullopt;
  if (!v.is_number() || !std::isfinite(v.get<double>()) || !(v.get<double>() >= lo && v.get<double>() <= hi))
    fail(key, what);
  return v.get<double>();
}

}  // namespace hfbake
