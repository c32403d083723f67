// The key registry: one table of every scenario key with its unit, accepted range, meaning,
// parser and printer. It drives parsing, the range checks, `demlab keys`, the reference page
// (docs/scenario-reference.md), the resolved scenario of a run and "did you mean".
#pragma once
#include <toml++/toml.h>

#include <functional>
#include <string>
#include <vector>

#include "scenario/scenario.h"

namespace demlab::keys {

struct Key {
    std::string name;      // dotted path, e.g. "material.density"
    std::string unit;      // "kg/m3", "-", "deg", ...
    std::string accepted;  // human-readable range
    std::string doc;
    std::function<void(Scenario&, const toml::node&, const std::string&)> set;
    std::function<std::string(const Scenario&)> get;  // TOML literal
};

// The table, in the order of the reference page and the resolved scenario.
const std::vector<Key>& registry();
const Key* find_key(const std::string& name);
std::vector<std::string> key_names();
// InputError "WHERE: unknown key; did you mean ...?"
// the name of `names` nearest to key (a few edits away), or "" (what "did you mean" offers)
std::string nearest(const std::string& key, const std::vector<std::string>& names);
[[noreturn]] void unknown_key(const std::string& where, const std::string& key, const std::vector<std::string>& names);

// Helpers of the parsers: "FILE:LINE: key 'KEY'", TOML literals, a node's text, checked reads.
std::string where_of(const std::string& file, const toml::node& n, const std::string& key);
std::string toml_number(double v);
std::string toml_string(const std::string& s);
std::string node_text(const toml::node& n);
double read_number(const toml::node& n, const std::string& where, const std::string& unit);
Vec2 read_vec2(const toml::node& n, const std::string& where, const std::string& unit);

}  // namespace demlab::keys
