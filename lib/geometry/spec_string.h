#pragma once
/// The `name:key=value,key=value` strings that name scenes, ray sets and accelerators.
///
/// Grammar: NAME [':' ITEM (',' ITEM)*], ITEM = KEY '=' VALUE | VALUE (a positional value).
/// A VALUE that holds commas or colons of its own (a nested spec) is wrapped in parentheses:
/// `stadium:object=(sphereflake:depth=2),ratio=1000`. A value without commas needs none:
/// `subdivided:of=cgal:bunny00,levels=2`.
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace raylab {

struct SpecString {
  std::string text;  ///< the whole spec, for messages
  std::string name;
  std::vector<std::string> positional;
  std::vector<std::pair<std::string, std::string>> params;
};

/// Parses a spec string. Throws InputError on unbalanced parentheses, empty names or keys, and
/// repeated keys.
SpecString parse_spec(std::string_view text);

/// `spec` with one more item `key_value` ("key=value"): `bvh` -> `bvh:key=value`,
/// `bvh:width=4` -> `bvh:width=4,key=value`.
inline std::string with_param(const std::string& spec, const std::string& key_value) {
  return spec + (spec.find(':') == std::string::npos ? ":" : ",") + key_value;
}

/// Documentation of one parameter, for listings and error messages.
struct ParamDoc {
  std::string key;
  std::string default_value;
  std::string description;
};

/// Typed, validated access to a spec's parameters in the style of pbrt-v4's ParameterDictionary:
/// every getter marks its key used; `finish()` rejects any key that no getter asked for, listing
/// the valid ones. Every getter throws InputError naming the spec, the key and the fault.
class SpecReader {
 public:
  explicit SpecReader(SpecString spec);

  const SpecString& spec() const { return spec_; }
  bool has(const std::string& key) const;
  std::string get_string(const std::string& key, const std::string& fallback);
  /// One of `choices`.
  std::string get_choice(const std::string& key, const std::string& fallback, const std::vector<std::string>& choices);
  /// An integer in [lo, hi].
  std::int64_t get_int(const std::string& key, std::int64_t fallback, std::int64_t lo, std::int64_t hi);
  /// A finite number in [lo, hi].
  double get_double(const std::string& key, double fallback, double lo, double hi);
  bool get_bool(const std::string& key, bool fallback);  ///< on|off|true|false|1|0
  /// The first positional value as an integer in [lo, hi]; `what` names it in messages.
  std::int64_t get_positional_int(const std::string& what, std::int64_t lo, std::int64_t hi);

  /// Throws when a key was given that no getter consumed, or when positional values were given
  /// that were not consumed. `valid` lists the accepted keys for the message.
  void finish(const std::vector<ParamDoc>& valid) const;
  /// Throws, as finish() does, for any key not in `valid`, before anything is read: lets a
  /// caller reject a bad spec before expensive work.
  void reject_unknown_keys(const std::vector<ParamDoc>& valid) const;

 private:
  const std::string* find(const std::string& key);
  SpecString spec_;
  std::vector<bool> used_;
  bool positional_used_ = false;
};

/// Parses a whole string as a finite double / an integer; false on any trailing garbage.
bool parse_double(std::string_view s, double& out);
bool parse_int(std::string_view s, std::int64_t& out);

}  // namespace raylab
