#pragma once
// Old spellings of the programs' flags, accepted until adaptseg 0.4 with a one-line notice
// (CHANGELOG.md lists every rename).

#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>
#include <vector>

namespace adaptseg::examples {

/// The --help group of the old spellings.
inline constexpr const char* kOldSpellings = "Old spellings (they go in adaptseg 0.4)";

/// The description of an old spelling: this prefix and the current spelling's name.
inline constexpr const char* kUseInstead = "use ";

/// Accepts `old_name` as another spelling of `current`, an option of `app` that stores into
/// `value`: the same value (--help lists it in its own group); once the command line has
/// parsed, tell_old_spellings() names the new spelling on standard error. Giving both is a
/// command-line error, and the old spelling excludes and needs whatever the current one does,
/// set before or after this call (inherit_old_spellings(), which parse_command_line() calls).
/// Returns the old spelling's option.
template <class T>
CLI::Option* accept_old_spelling(CLI::App& app, CLI::Option* current, const std::string& old_name, T& value) {
  // In its own --help group, its description the new spelling.
  CLI::Option* old = app.add_option(old_name, value, kUseInstead + current->get_name())->group(kOldSpellings);
  old->excludes(current);
  return old;
}

/// The old values given on this command line (accept_old_value()), for tell_old_spellings().
inline std::vector<std::string>& old_values_given() {
  static std::vector<std::string> given;
  return given;
}

/// Accepts `old_value` as another spelling of `new_value` for `option` (a choice renamed, as
/// `--segmenter network` became `--segmenter network`): the option stores `new_value`, and once
/// the command line has parsed, tell_old_spellings() names the new spelling on standard error.
/// Call it before the option's choices are checked (before `->check(CLI::IsMember(...))`).
inline CLI::Option* accept_old_value(CLI::Option* option, const std::string& old_value, const std::string& new_value) {
  // The value taken by const reference: a callable taking it by value trips GCC 12's
  // -Wmaybe-uninitialized at -O3 (a false positive inside std::function).
  struct Rename {
    std::string from, to, notice;
    std::string operator()(const std::string& value) const {
      if (value != from) return value;
      old_values_given().push_back(notice);
      return to;
    }
  };
  const std::string notice = option->get_name() + " " + old_value + " is deprecated and goes in adaptseg 0.4: use " +
                             option->get_name() + " " + new_value;
  return option->transform(Rename{old_value, new_value, notice}, "", "old value " + old_value);
}

/// Before parsing: each old spelling of `app` excludes every option its current spelling
/// excludes (or is excluded by) and needs what it needs, so that a program states its rules
/// once, for the current names.
inline void inherit_old_spellings(CLI::App& app) {
  const std::string prefix = kUseInstead;
  for (CLI::Option* old : app.get_options([](const CLI::Option* o) { return o->get_group() == kOldSpellings; })) {
    const std::string& description = old->get_description();
    if (description.rfind(prefix, 0) != 0) continue;
    CLI::Option* current = app.get_option_no_throw(description.substr(prefix.size()));
    if (current == nullptr) continue;
    // CLI11's exclusions are symmetric: the current spelling's set holds every option that
    // excludes it, whichever side stated it.
    for (CLI::Option* other : current->get_excludes())
      if (other != old) old->excludes(other);
    for (CLI::Option* other : current->get_needs()) old->needs(other);
  }
}

/// After a successful parse: one line on stderr per old spelling given (accept_old_spelling(),
/// accept_old_value()).
inline void tell_old_spellings(const CLI::App& app) {
  for (const CLI::Option* o : app.get_options())
    if (o->get_group() == kOldSpellings && o->count() > 0)
      std::fprintf(stderr, "%s is deprecated and goes in adaptseg 0.4: %s\n", o->get_name().c_str(),
                   o->get_description().c_str());
  for (const std::string& notice : old_values_given()) std::fprintf(stderr, "%s\n", notice.c_str());
  old_values_given().clear();
}

}  // namespace adaptseg::examples
