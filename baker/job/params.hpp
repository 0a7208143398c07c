// The one reader of a bake entry's (or the reference's) parameters. It knows the job file and the JSON
// pointer of the object it reads, so every refusal is one line naming both ("<file>: /bake/2/normal_bins:
// must be ..."), and it records every value a method reads, defaults included: resolved() is what the bake
// actually used (written to the EXR metadata and report.json as the method's parameters).
//
// A method's reader (methods/method_table.hpp) reads its keys with the typed getters below once per bake
// entry, when the job is resolved (validate and bake alike), into the method's typed config; nothing reads
// the entry again. A method that derives a value (a default that depends on other keys) records it with
// resolve().
#pragma once

#include <functional>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hfbake {

class Params {
 public:
  // `object` is the JSON object read (kept by reference: it must outlive the reader); `file` and `pointer`
  // (e.g. "/bake/2") name it in errors. Both may be empty (a method called directly from code or a test).
  explicit Params(const nlohmann::json& object, std::string file = "", std::string pointer = "");

  bool has(const char* key) const { return object_.is_object() && object_.contains(key); }
  // The value as written (has(key) must hold).
  const nlohmann::json& raw(const char* key) const { return object_.at(key); }

  // An integer in [lo, hi], or `fallback` when absent.
  int integer(const char* key, int fallback, int lo, int hi);
  // A finite number in [lo, hi], or `fallback` when absent.
  double number(const char* key, double fallback, double lo, double hi);
  bool boolean(const char* key, bool fallback);
  // One of `allowed` (the error lists them), or `fallback` when absent.
  std::string choice(const char* key, const std::string& fallback,
                     std::initializer_list<const char*> allowed);
  // A string of at most max_length characters, or nullopt when absent (then nothing is recorded).
  std::optional<std::string> text(const char* key, std::size_t max_length);
  // "layers": each must be in `known` (else the error lists what the method writes), none twice, at least
  // one; `defaults` when absent. Recorded as resolved "layers".
  std::vector<std::string> layers(const std::vector<std::string>& known,
                                  const std::vector<std::string>& defaults);
  // A number for which ok(x) holds (anything else fails with `what`); has(key) must hold. Recorded.
  double number_that(const char* key, bool (*ok)(double), const std::string& what);
  // A value that is either the word `word` (nullopt) or a finite number in [lo, hi]; anything else fails
  // with `what`. has(key) must hold; nothing is recorded.
  std::optional<double> word_or_number(const char* key, const char* word, double lo, double hi,
                                       const std::string& what) const;

  // A nested object: `read` reads it with a reader of its own (errors name pointer + "/" + key), whose
  // record is then recorded here under key. Returns false, reading nothing, when absent; fails unless an
  // object.
  bool object(const char* key, const std::function<void(Params&)>& read);

  // Records a value the method derived (it replaces what a getter recorded under that key).
  void resolve(const char* key, nlohmann::json value) { resolved_[key] = std::move(value); }
  const nlohmann::json& resolved() const { return resolved_; }
  // The layers layers() returned (empty when the reader never called it).
  const std::vector<std::string>& resolved_layers() const { return layers_; }

  // Throws InputError(file, pointer + "/" + key, what). key may be empty (the object itself).
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

  const std::string& file() const { return file_; }
  const std::string& pointer() const { return pointer_; }

 private:
  const nlohmann::json& object_;
  std::string file_, pointer_;
  nlohmann::json resolved_ = nlohmann::json::object();
  std::vector<std::string> layers_;
};

// "a", "b" or "c": for messages that list allowed values.
std::string quoted_list(const std::vector<std::string>& names);

}  // namespace hfbake
