#pragma once
/// \file The options of a configuration as a table: each declared once by a macro of rows
/// X(name, type, member, unit, check, rule, help), from which the configuration's validate(),
/// the command line's flags, the Python keywords, the JSON fields and the help texts follow.
/// `type` is double, or std::optional<double> for an option that may be off (none); `member`
/// is the configuration's member that holds it (a path: walk.max_ray_depth); `check`, an
/// expression of the value `v`, must hold, else the error names the option, its value and
/// `rule`. The default is the member's own.

#include "nbv/errors.hpp"

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

namespace nbv {

/// A row of an option table as data, for the front doors that loop over the options.
template <class Config>
struct OptionRow {
  const char* name;
  bool optional;     ///< may be none (off)
  const char* unit;  ///< "m", "s", "ms" or ""
  const char* rule;  ///< what validate() requires of it
  const char* help;  ///< what it does
  /// The option's value in `config` (none: off).
  std::optional<double> (*get)(const Config& config);
  /// Sets it; none for an option that is not optional throws InvalidArgument.
  void (*set)(Config& config, std::optional<double> value);
};

/// The row named `name` of `rows`, or null.
template <class Config>
const OptionRow<Config>* optionRow(std::span<const OptionRow<Config>> rows, std::string_view name) {
  for (const OptionRow<Config>& row : rows) {
    if (name == row.name) return &row;
  }
  return nullptr;
}

namespace option_detail {

inline std::string text(double v) { return numberText(v); }
inline std::string text(const std::optional<double>& v) { return v ? numberText(*v) : "none"; }

inline void assign(double& member, std::optional<double> value, const char* name) {
  if (!value) throw InvalidArgument(std::string(name) + " takes a number, not none");
  member = *value;
}
inline void assign(std::optional<double>& member, std::optional<double> value, const char*) { member = value; }

}  // namespace option_detail
}  // namespace nbv

/// A row of a table X(name, type, member, unit, check, rule, help) as an OptionRow<Config>.
#define NBV_OPTION_ROW(Config, name, type, member, unit, check, rule, help)                              \
  ::nbv::OptionRow<Config>{#name,                                                                         \
                           std::is_same_v<type, std::optional<double>>,                                    \
                           unit,                                                                           \
                           rule,                                                                           \
                           help,                                                                           \
                           [](const Config& c) -> std::optional<double> { return c.member; },             \
                           [](Config& c, std::optional<double> value) {                                    \
                             ::nbv::option_detail::assign(c.member, value, #name);                         \
                           }},

/// The check of a row inside Config::validate(), `c` the configuration: InvalidArgument
/// "invalid WHAT option: NAME = VALUE (RULE)" unless `check` holds.
#define NBV_OPTION_CHECK(what, name, type, member, unit, check, rule, help)                               \
  if (const type& v = c.member; !(check)) {                                                                \
    throw ::nbv::InvalidArgument("invalid " what " option: " #name " = " + ::nbv::option_detail::text(v) + \
                                 " (" rule ")");                                                           \
  }
