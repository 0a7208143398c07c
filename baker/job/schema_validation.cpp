#include "job/schema_validation.hpp"

// GCC 12 reports a false -Wrestrict inside valijson's json_pointer string handling (inlined
// std::string::replace); it is not in hfbake's code and the TU is otherwise warning-free.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wrestrict"
#endif

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <regex>
#include <stdexcept>
#include <valijson/adapters/nlohmann_json_adapter.hpp>
#include <valijson/schema.hpp>
#include <valijson/schema_parser.hpp>
#include <valijson/validator.hpp>

#include "job/embedded_schemas.hpp"

namespace hfbake {
namespace {

// Removes "uniqueItems" from a schema: valijson reports every equal pair (n^2 / 2 lines for one value
// listed n times); hfbake checks it itself, once per value (unique_items_violations).
void drop_unique_items(nlohmann::json& node) {
  if (node.is_object()) {
    node.erase("uniqueItems");
    for (auto& [key, child] : node.items())
      if (key != "enum" && key != "const" && key != "default") drop_unique_items(child);
  } else if (node.is_array()) {
    for (auto& child : node) drop_unique_items(child);
  }
}

// The embedded schemas, parsed once per process (immutable; thread-safe via a function-local static):
// as written (`as_written`), or as valijson reads them (without "uniqueItems").
const nlohmann::json& schema_document(const std::string& path, bool as_written = true) {
  using Docs = std::map<std::string, nlohmann::json>;
  static const std::pair<Docs, Docs> docs = [] {
    std::pair<Docs, Docs> m;
    for (const EmbeddedSchema& s : embedded_schemas()) {
      nlohmann::json doc = nlohmann::json::parse(s.text.begin(), s.text.end());
      m.first.emplace(std::string(s.path), doc);
      drop_unique_items(doc);
      m.second.emplace(std::string(s.path), std::move(doc));
    }
    return m;
  }();
  const Docs& d = as_written ? docs.first : docs.second;
  auto it = d.find(path);
  if (it == d.end()) throw std::logic_error("hfbake: no embedded schema " + path);
  return it->second;
}

// valijson asks for referenced documents by the URI written in "$ref" (relative to the referring
// document's folder for nested files): map it onto the embedded file set.
std::string resolve_schema_uri(const std::string& uri) {
  std::string p = uri;
  const auto hash = p.find('#');
  if (hash != std::string::npos) p.resize(hash);
  for (const EmbeddedSchema& s : embedded_schemas()) {
    const std::string known(s.path);
    if (p == known) return known;
    if (p.size() > known.size() && p.compare(p.size() - known.size(), known.size(), known) == 0 &&
        p[p.size() - known.size() - 1] == '/')
      return known;
  }
  // "environment.schema.json" referenced from inside methods/ resolves to the top folder.
  const auto slash = p.rfind('/');
  if (slash != std::string::npos) return resolve_schema_uri(p.substr(slash + 1));
  // A bare name not in the top folder: a sibling inside a subfolder ("obscurance_common.schema.json" from
  // methods/hbao.schema.json), when exactly one subfolder has it.
  std::string sibling;
  for (const EmbeddedSchema& s : embedded_schemas()) {
    const std::string known(s.path);
    if (known.size() > p.size() + 1 && known.compare(known.size() - p.size(), p.size(), p) == 0 &&
        known[known.size() - p.size() - 1] == '/') {
      if (!sibling.empty()) throw std::logic_error("hfbake: ambiguous schema reference " + uri);
      sibling = known;
    }
  }
  if (!sibling.empty()) return sibling;
  throw std::logic_error("hfbake: schema reference to unknown document " + uri);
}

// Turns valijson's context ["<root>", "[bake]", "[0]", "[directions]"] into "/bake/0/directions".
std::string pointer_of(const std::vector<std::string>& context) {
  std::string ptr;
  for (const std::string& c : context) {
    if (c == "<root>") continue;
    std::string token = c;
    if (token.size() >= 2 && token.front() == '[' && token.back() == ']')
      token = token.substr(1, token.size() - 2);
    // JSON pointer escaping (RFC 6901).
    std::string escaped;
    for (char ch : token) {
      if (ch == '~')
        escaped += "~0";
      else if (ch == '/')
        escaped += "~1";
      else
        escaped += ch;
    }
    ptr += "/" + escaped;
  }
  return ptr;
}

// Rewrites valijson's sentences into short rules ("must be >= 1"). Unrecognised sentences pass through.
SchemaViolation rewrite(std::string pointer, std::string text) {
  std::smatch m;
  auto num = [](std::string s) {
    // valijson prints numbers with std::to_string: "1.000000" -> "1"; a bound of 1e30, all its digits
    // ("1000000000000000019884624838656.000000") -> "1e+30", the shortest text of the double.
    if (s.find('.') != std::string::npos) {
      while (!s.empty() && s.back() == '0') s.pop_back();
      if (!s.empty() && s.back() == '.') s.pop_back();
    }
    if (s.size() > 15 && s.find_first_not_of("-0123456789") == std::string::npos) {
      try {
        return nlohmann::json(std::stod(s)).dump();
      } catch (const std::exception&) {
      }
    }
    return s;
  };
  static const std::regex min_re(R"(Expected number greater than or equal to ([-0-9.e+]+))");
  static const std::regex xmin_re(R"(Expected number greater than ([-0-9.e+]+))");
  static const std::regex max_re(R"(Expected number less than or equal to ([-0-9.e+]+))");
  static const std::regex xmax_re(R"(Expected number less than ([-0-9.e+]+))");
  static const std::regex unknown_re(
      R"(Object contains a property that could not be validated using 'properties' or 'additionalProperties' constraints: '([\s\S]*)'\.?)");
  static const std::regex missing_re(R"(Missing required property '([\s\S]*)'\.?)");
  static const std::regex type_re(R"(Value type not permitted by 'type' constraint\.?)");
  static const std::regex enum_re(R"(Failed to match against any enum values\.?)");
  static const std::regex min_items_re(R"(Array should contain no fewer than (\d+) elements\.?)");
  static const std::regex max_items_re(R"(Array should contain no more than (\d+) elements\.?)");
  static const std::regex min_length_re(R"(String should be no fewer than (\d+) characters in length\.?)",
                                        std::regex::icase);
  if (std::regex_search(text, m, min_length_re))
    return {pointer,
            m[1].str() == "1" ? "must not be empty" : "must be at least " + m[1].str() + " characters"};
  if (std::regex_search(text, m, min_re)) return {pointer, "must be >= " + num(m[1])};
  if (std::regex_search(text, m, xmin_re)) return {pointer, "must be > " + num(m[1])};
  if (std::regex_search(text, m, max_re)) return {pointer, "must be <= " + num(m[1])};
  if (std::regex_search(text, m, xmax_re)) return {pointer, "must be < " + num(m[1])};
  if (std::regex_search(text, m, unknown_re)) {
    pointer.append("/").append(m[1].str());
    return {std::move(pointer), "unknown key"};
  }
  if (std::regex_search(text, m, missing_re)) return {pointer, "missing required key \"" + m[1].str() + "\""};
  if (std::regex_search(text, m, type_re)) return {pointer, "wrong type"};
  if (std::regex_search(text, m, enum_re)) return {pointer, "not one of the allowed values"};
  if (std::regex_search(text, m, min_items_re))
    return {pointer, "must have at least " + m[1].str() + " items"};
  if (std::regex_search(text, m, max_items_re))
    return {pointer, "must have at most " + m[1].str() + " items"};
  if (!text.empty() && text.back() == '.') text.pop_back();
  if (!text.empty()) text[0] = char(std::tolower(static_cast<unsigned char>(text[0])));
  return {pointer, text};
}

// Messages valijson emits for an enclosing value when something inside it failed: not leaf causes.
bool is_wrapper(const std::string& text) {
  static const char* wrappers[] = {"Failed to validate item #",
                                   "Failed to validate against schema associated with property name",
                                   "Failed to validate against child schema",
                                   "Failed to validate against any child schemas",
                                   "Failed to validate against any schemas allowed by anyOf",
                                   "Failed to validate against schema referenced by",
                                   "Failed to validate against 'then' subschema",
                                   "Failed to validate against 'else' subschema",
                                   "Failed to validate additional properties",
                                   "Failed to validate against additional properties",
                                   "Failed to validate value against additionalProperties",
                                   "Failed to validate against a conditional schema"};
  for (const char* w : wrappers)
    if (text.rfind(w, 0) == 0) return true;
  return false;
}

// Follows "$ref" (local "#/..." or another embedded file, optionally with a fragment) from `doc`'s node.
const nlohmann::json* follow_ref(const nlohmann::json* node, std::string& doc_path) {
  for (int guard = 0; node && node->is_object() && node->contains("$ref") && guard < 16; ++guard) {
    const std::string ref = (*node)["$ref"].get<std::string>();
    const auto hash = ref.find('#');
    if (hash != 0) doc_path = resolve_schema_uri(ref.substr(0, hash));
    const nlohmann::json& doc = schema_document(doc_path);
    const std::string fragment = hash == std::string::npos ? "" : ref.substr(hash + 1);
    const nlohmann::json::json_pointer ptr(fragment);
    node = doc.contains(ptr) ? &doc.at(ptr) : nullptr;
  }
  return node;
}

// The values of `keyword` ("enum", "maxLength", "type") the schema gives the value at the pointer `tokens`,
// walking properties and items (and $ref); the branches of allOf/anyOf/oneOf and if-then are searched too,
// each branch's value appended in the schema's order.
void keywords_at(const nlohmann::json* node, std::string doc_path, const std::vector<std::string>& tokens,
                 std::size_t k, const char* keyword, std::vector<const nlohmann::json*>& found) {
  node = follow_ref(node, doc_path);
  if (!node || !node->is_object()) return;
  if (k == tokens.size() && node->contains(keyword)) found.push_back(&(*node)[keyword]);
  if (k < tokens.size()) {
    const std::string& t = tokens[k];
    if (node->contains("properties") && (*node)["properties"].contains(t))
      keywords_at(&(*node)["properties"][t], doc_path, tokens, k + 1, keyword, found);
    else if (node->contains("additionalProperties") && (*node)["additionalProperties"].is_object())
      keywords_at(&(*node)["additionalProperties"], doc_path, tokens, k + 1, keyword, found);
    if (node->contains("items") && !t.empty() && std::all_of(t.begin(), t.end(), ::isdigit))
      keywords_at(&(*node)["items"], doc_path, tokens, k + 1, keyword, found);
  }
  for (const char* branch : {"allOf", "anyOf", "oneOf"})
    if (node->contains(branch))
      for (const auto& b : (*node)[branch]) {
        keywords_at(&b, doc_path, tokens, k, keyword, found);
        if (b.contains("then")) keywords_at(&b["then"], doc_path, tokens, k, keyword, found);
      }
}

// The first of keywords_at's values, or nullptr when the schema gives none.
const nlohmann::json* keyword_at(const nlohmann::json* node, const std::string& doc_path,
                                 const std::vector<std::string>& tokens, std::size_t k, const char* keyword) {
  std::vector<const nlohmann::json*> found;
  keywords_at(node, doc_path, tokens, k, keyword, found);
  return found.empty() ? nullptr : found.front();
}

std::vector<std::string> pointer_tokens(const std::string& pointer) {
  std::vector<std::string> tokens;
  for (std::size_t a = 1; a <= pointer.size() && !pointer.empty();) {
    const std::size_t b = pointer.find('/', a);
    tokens.push_back(pointer.substr(a, b == std::string::npos ? std::string::npos : b - a));
    if (b == std::string::npos) break;
    a = b + 1;
  }
  return tokens;
}

// Calls visit(leaf, tokens) for every value of the document that is neither an object nor an array, tokens
// its JSON pointer's.
template <class Visit>
void for_each_leaf(const nlohmann::json& value, std::vector<std::string>& tokens, const Visit& visit) {
  if (!value.is_object() && !value.is_array()) return visit(value, tokens);
  std::size_t index = 0;
  for (const auto& [key, child] : value.items()) {
    tokens.push_back(value.is_array() ? std::to_string(index++) : key);
    for_each_leaf(child, tokens, visit);
    tokens.pop_back();
  }
}

std::string pointer_of_tokens(const std::vector<std::string>& tokens) {
  std::string pointer;
  for (const std::string& t : tokens) pointer += "/" + t;
  return pointer;
}

// Strings longer than the schema's "maxLength" for them, checked before valijson matches any "pattern"
// (std::regex recurses once per character).
void overlong_string(const nlohmann::json& value, const std::string& schema_path,
                     const std::vector<std::string>& tokens, std::vector<SchemaViolation>& out) {
  if (!value.is_string()) return;
  const nlohmann::json* limit =
      keyword_at(&schema_document(schema_path), schema_path, tokens, 0, "maxLength");
  const std::size_t n = value.get_ref<const std::string&>().size();
  if (limit && limit->is_number_unsigned() && n > limit->get<std::size_t>())
    out.push_back({pointer_of_tokens(tokens), "must be at most " + limit->dump() +
                                                  " characters long (it has " + std::to_string(n) + ")"});
}

// A whole number beyond a 64-bit integer where the schema asks for an integer (2^63 and up, or a number like
// 1e20 or 18446744073709551616 that JSON holds as a float): the validator would wrap it, or call it not an
// integer. Checked first, said with the schema's bound ("must be <= 4096") or the 64-bit one.
void oversized_integer(const nlohmann::json& value, const std::string& schema_path,
                       const std::vector<std::string>& tokens, std::vector<SchemaViolation>& out) {
  if (!value.is_number_unsigned() && !value.is_number_float()) return;
  constexpr double k2p63 = 9223372036854775808.0;
  bool over = false, under = false;
  if (value.is_number_unsigned()) {
    over = value.get<std::uint64_t>() > std::uint64_t(std::numeric_limits<std::int64_t>::max());
  } else {
    const double x = value.get<double>();
    over = std::isfinite(x) && x == std::floor(x) && x >= k2p63;
    under = std::isfinite(x) && x == std::floor(x) && x < -k2p63;
  }
  if (!over && !under) return;
  std::vector<const nlohmann::json*> types;
  keywords_at(&schema_document(schema_path), schema_path, tokens, 0, "type", types);
  const bool integer = std::any_of(types.begin(), types.end(), [](const nlohmann::json* t) {
    return *t == "integer" || (t->is_array() && std::find(t->begin(), t->end(), "integer") != t->end());
  });
  if (!integer) return;
  const nlohmann::json* bound =
      keyword_at(&schema_document(schema_path), schema_path, tokens, 0, over ? "maximum" : "minimum");
  out.push_back({pointer_of_tokens(tokens),
                 bound && bound->is_number()
                     ? std::string(over ? "must be <= " : "must be >= ") + bound->dump() + " (it is " +
                           value.dump() + ")"
                     : std::string("is ") + value.dump() + ", beyond a 64-bit integer (" +
                           (over ? "at most 9223372036854775807" : "at least -9223372036854775808") + ")"});
}

// Arrays whose schema says "uniqueItems": one line per value listed more than once, at its second place.
void repeated_items(const nlohmann::json& value, const std::string& schema_path,
                    std::vector<std::string>& tokens, std::vector<SchemaViolation>& out) {
  if (!value.is_object() && !value.is_array()) return;
  std::string pointer;
  for (const std::string& t : tokens) pointer += "/" + t;
  if (value.is_array()) {
    const nlohmann::json* unique =
        keyword_at(&schema_document(schema_path), schema_path, tokens, 0, "uniqueItems");
    if (unique && *unique == true) {
      std::map<std::string, std::vector<std::size_t>> places;
      std::vector<std::string> order;
      for (std::size_t i = 0; i < value.size(); ++i) {
        std::vector<std::size_t>& p = places[value[i].dump()];
        if (p.size() == 1) order.push_back(value[i].dump());
        p.push_back(i);
      }
      for (const std::string& v : order) {
        const std::vector<std::size_t>& p = places[v];
        const std::string shown = v.size() > 64 ? v.substr(0, 61) + "..." : v;
        out.push_back({pointer + "/" + std::to_string(p[1]),
                       shown + " is listed " + std::to_string(p.size()) + " times (first as item " +
                           std::to_string(p[0]) + "); each may be listed once"});
      }
    }
  }
  std::size_t index = 0;
  for (const auto& [key, child] : value.items()) {
    tokens.push_back(value.is_array() ? std::to_string(index++) : key);
    repeated_items(child, schema_path, tokens, out);
    tokens.pop_back();
  }
}

std::string allowed_values(const std::string& schema_path, const std::string& pointer) {
  const std::vector<std::string> tokens = pointer_tokens(pointer);
  const nlohmann::json* e = keyword_at(&schema_document(schema_path), schema_path, tokens, 0, "enum");
  if (!e || !e->is_array()) return "";
  std::string list;
  for (std::size_t i = 0; i < e->size(); ++i) list += (i ? ", " : "") + (*e)[i].dump();
  return list;
}

// "an integer", "a number or an array": the JSON types the schema allows at the pointer, in its order.
std::string allowed_types(const std::string& schema_path, const std::string& pointer) {
  std::vector<const nlohmann::json*> found;
  keywords_at(&schema_document(schema_path), schema_path, pointer_tokens(pointer), 0, "type", found);
  std::vector<std::string> names;
  auto add = [&](const nlohmann::json& t) {
    if (!t.is_string()) return;
    const std::string n = t.get<std::string>();
    const std::string a = n == "integer" || n == "array" || n == "object" ? "an " + n
                          : n == "boolean"                                ? "true or false"
                                                                          : "a " + n;
    if (std::find(names.begin(), names.end(), a) == names.end()) names.push_back(a);
  };
  for (const nlohmann::json* t : found) {
    if (t->is_array())
      for (const auto& e : *t) add(e);
    else
      add(*t);
  }
  std::string list;
  for (std::size_t i = 0; i < names.size(); ++i)
    list += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  return list;
}

// What the job holds at the pointer, as a type: "a string", "an array", "null".
std::string given_type(const nlohmann::json& doc, const std::string& pointer) {
  const nlohmann::json* at = nullptr;
  try {
    const nlohmann::json::json_pointer ptr(pointer);
    if (doc.contains(ptr)) at = &doc.at(ptr);
  } catch (const nlohmann::json::exception&) {
  }
  if (!at) return "";
  const nlohmann::json& v = *at;
  if (v.is_boolean()) return v.dump();
  if (v.is_number_integer() || v.is_number_unsigned()) return "an integer";
  // A whole number written with a fraction or an exponent (16.0, 1.6e1): integers are written without
  // either (docs/job-reference.md).
  if (v.is_number_float()) {
    const double x = v.get<double>();
    if (std::fabs(x) < 1e15 && x == std::floor(x))
      return v.dump() + ", written with a fraction or an exponent: write " +
             std::to_string(static_cast<long long>(x));
    return v.dump();
  }
  if (v.is_null()) return "null";
  return v.is_array() ? "an array" : v.is_object() ? "an object" : "a string";
}

// Edits between a and b, ASCII case ignored: insertions, deletions, substitutions and swaps of two
// neighbours (the optimal string alignment distance).
std::size_t edits_between(const std::string& a, const std::string& b) {
  const auto low = [](char c) { return char(std::tolower(static_cast<unsigned char>(c))); };
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i)
    for (std::size_t j = 1; j <= m; ++j) {
      const bool same = low(a[i - 1]) == low(b[j - 1]);
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (same ? 0 : 1)});
      if (i > 1 && j > 1 && low(a[i - 1]) == low(b[j - 2]) && low(a[i - 2]) == low(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[n][m];
}

// For an unknown key at `pointer`: the key the schema allows beside it that is closest to it, when one is
// within two edits (one for a key of four characters or fewer) and no other is as close; else "".
// The alternatives (oneOf) of the schema at pointer when each only requires keys, else null.
const nlohmann::json* keys_only_one_of(const std::string& schema_path, const std::string& pointer) {
  const nlohmann::json* o =
      keyword_at(&schema_document(schema_path), schema_path, pointer_tokens(pointer), 0, "oneOf");
  if (!o || !o->is_array() || o->empty()) return nullptr;
  for (const nlohmann::json& b : *o)
    if (!b.is_object() || b.size() != 1 || !b.contains("required") || !b["required"].is_array() ||
        b["required"].empty())
      return nullptr;
  return o;
}

// "needs exactly one of image or procedural": keys_only_one_of's alternatives named; "" without them.
std::string one_of_keys(const std::string& schema_path, const std::string& pointer) {
  const nlohmann::json* o = keys_only_one_of(schema_path, pointer);
  if (!o) return "";
  std::string list;
  for (std::size_t i = 0; i < o->size(); ++i) {
    const nlohmann::json& req = (*o)[i]["required"];
    std::string keys;
    for (std::size_t k = 0; k < req.size(); ++k)
      keys += (k == 0 ? "" : " and ") + (req[k].is_string() ? req[k].get<std::string>() : req[k].dump());
    list += (i == 0 ? "" : i + 1 == o->size() ? " or " : ", ") + keys;
  }
  return "needs exactly one of " + list;
}

std::string closest_known_key(const std::string& schema_path, const std::string& pointer) {
  std::vector<std::string> tokens = pointer_tokens(pointer);
  if (tokens.empty()) return "";
  const std::string key = tokens.back();
  tokens.pop_back();
  std::vector<const nlohmann::json*> found;
  keywords_at(&schema_document(schema_path), schema_path, tokens, 0, "properties", found);
  const std::size_t most = key.size() <= 4 ? 1 : 2;
  std::string best;
  std::size_t best_edits = most + 1;
  bool tie = false;
  for (const nlohmann::json* properties : found) {
    if (!properties->is_object()) continue;
    for (const auto& [name, schema] : properties->items()) {
      if (name == best) continue;
      const std::size_t e = edits_between(key, name);
      if (e < best_edits)
        best = name, best_edits = e, tie = false;
      else if (e == best_edits)
        tie = true;
    }
  }
  return best_edits <= most && !tie ? best : "";
}

}  // namespace

std::vector<SchemaViolation> validate_against_schema(const nlohmann::json& doc,
                                                     const std::string& schema_path) {
  using Adapter = valijson::adapters::NlohmannJsonAdapter;
  {
    std::vector<std::string> tokens;
    std::vector<SchemaViolation> overlong;
    for_each_leaf(doc, tokens, [&](const nlohmann::json& v, const std::vector<std::string>& at) {
      overlong_string(v, schema_path, at, overlong);
      oversized_integer(v, schema_path, at, overlong);
    });
    if (!overlong.empty()) return overlong;
  }
  // Parsing the schema is cheap (a few KB); keep it per call so there is no shared mutable state.
  valijson::Schema schema;
  valijson::SchemaParser parser;
  const Adapter schema_adapter(schema_document(schema_path, false));
  parser.populateSchema(
      schema_adapter, schema,
      [](const std::string& uri) -> const nlohmann::json* {
        return &schema_document(resolve_schema_uri(uri), false);
      },
      [](const nlohmann::json*) {});

  valijson::Validator validator;
  valijson::ValidationResults results;
  const Adapter target(doc);
  validator.validate(schema, target, &results);

  std::vector<SchemaViolation> out;
  {
    std::vector<std::string> tokens;
    repeated_items(doc, schema_path, tokens, out);
  }
  valijson::ValidationResults::Error error;
  std::vector<std::pair<std::string, std::string>> raw;
  while (results.popError(error)) raw.emplace_back(pointer_of(error.context), error.description);
  for (const auto& [pointer, text] : raw) {
    if (is_wrapper(text)) continue;
    SchemaViolation v = rewrite(pointer, text);
    if (v.message == "unknown key")
      if (const std::string known = closest_known_key(schema_path, v.pointer); !known.empty())
        v.message += " (did you mean \"" + known + "\"?)";
    if (v.message == "not one of the allowed values")
      if (const std::string list = allowed_values(schema_path, v.pointer); !list.empty())
        v.message = "must be one of " + list;
    const bool duplicate = std::any_of(out.begin(), out.end(), [&](const SchemaViolation& o) {
      return o.pointer == v.pointer && o.message == v.message;
    });
    if (!duplicate) out.push_back(std::move(v));
  }
  // An alternative (oneOf/anyOf) that failed produces messages for every branch; when a value failed
  // only through alternatives, keep the summarising message instead of the branches' contradictions.
  if (out.empty() && !raw.empty()) out.push_back(rewrite(raw.front().first, raw.front().second));
  // One value, one line: when a value fails several branches of an alternative (a number or [r, g, b]; a
  // number or "from_file"), the branches whose type or constant did not match say nothing about it: keep
  // the branch that did ("must be <= 1", not also "wrong type").
  auto says_nothing = [](const SchemaViolation& v) {
    return v.message == "wrong type" ||
           v.message.rfind("failed to match expected value set by 'const'", 0) == 0;
  };
  // When every branch says only that (a string where a number or a constant is expected), one of them.
  std::vector<SchemaViolation> kept;
  for (const SchemaViolation& v : out) {
    // Another branch that failed on the value, or matched the type and failed inside it, says more.
    const bool other = std::any_of(out.begin(), out.end(), [&](const SchemaViolation& o) {
      return &o != &v &&
             ((o.pointer == v.pointer && !says_nothing(o)) || o.pointer.rfind(v.pointer + "/", 0) == 0);
    });
    const bool said = std::any_of(kept.begin(), kept.end(),
                                  [&](const SchemaViolation& o) { return o.pointer == v.pointer; });
    if (!(says_nothing(v) && (other || said))) kept.push_back(v);
  }
  // The lines that are kept say what was expected: "must be an integer (it is a string)", "must be 1".
  for (SchemaViolation& v : kept) {
    // A bound as the schema writes it where valijson's text (six decimals) lost it: 1e-30 read "0".
    for (const auto& [lead, keyword] :
         {std::pair{"must be >= ", "minimum"}, std::pair{"must be <= ", "maximum"},
          std::pair{"must be > ", "exclusiveMinimum"}, std::pair{"must be < ", "exclusiveMaximum"}})
      if (v.message.rfind(lead, 0) == 0)
        if (const nlohmann::json* b =
                keyword_at(&schema_document(schema_path), schema_path, pointer_tokens(v.pointer), 0, keyword);
            b && b->is_number()) {
          const std::string said = v.message.substr(std::strlen(lead));
          char* end = nullptr;
          const double read = std::strtod(said.c_str(), &end);
          if (end == said.c_str() || read != b->get<double>()) v.message = lead + b->dump();
        }
    if (v.message == "wrong type") {
      const std::string want = allowed_types(schema_path, v.pointer), got = given_type(doc, v.pointer);
      if (!want.empty()) v.message = "must be " + want + (got.empty() ? "" : " (it is " + got + ")");
    } else if (v.message.rfind("failed to match expected value set by 'const'", 0) == 0) {
      const nlohmann::json* c =
          keyword_at(&schema_document(schema_path), schema_path, pointer_tokens(v.pointer), 0, "const");
      if (c) v.message = "must be " + c->dump();
    } else if (v.message.rfind("failed to match regex", 0) == 0) {
      const nlohmann::json* p =
          keyword_at(&schema_document(schema_path), schema_path, pointer_tokens(v.pointer), 0, "pattern");
      if (p && p->is_string()) v.message = "must match the pattern " + p->get<std::string>();
    } else if (v.message.rfind("failed to validate against exactly one child schema", 0) == 0) {
      if (const std::string one = one_of_keys(schema_path, v.pointer); !one.empty()) v.message = one;
    }
  }
  // A key missing from an object whose alternatives each require keys (an image or a procedural field;
  // a texture's layers or its pack and channels), or a key another needs among them: one line naming the
  // alternatives, not a line for each branch's missing key, which contradict each other.
  std::vector<SchemaViolation> lines;
  for (SchemaViolation& v : kept) {
    for (const std::string lead : {"missing required key \"", "missing dependency '"}) {
      if (v.message.rfind(lead, 0) != 0 || v.message.size() <= lead.size() + 1) continue;
      const std::string key = v.message.substr(lead.size(), v.message.size() - lead.size() - 1);
      if (const nlohmann::json* o = keys_only_one_of(schema_path, v.pointer))
        for (const nlohmann::json& branch : *o)
          for (const nlohmann::json& k : branch["required"])
            if (k == key) v.message = one_of_keys(schema_path, v.pointer);
      break;
    }
    const bool duplicate = std::any_of(lines.begin(), lines.end(), [&](const SchemaViolation& o) {
      return o.pointer == v.pointer && o.message == v.message;
    });
    if (!duplicate) lines.push_back(std::move(v));
  }
  return lines;
}

}  // namespace hfbake
