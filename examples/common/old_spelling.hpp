#pragma once
// Old spellings of the programs' flags, accepted until adaptseg 0.4 with a one-line notice
// (CHANGELOG.md lists every rename).

#include <CLI/CLI.hpp>

#include <cstdio>
#include <string>

namespace adaptseg::examples {

/// The --help group of the old spellings.
inline constexpr const char* kOldSpellings = "Old spellings (they go in adaptseg 0.4)";

/// Accepts `old_name` as another spelling of `current`, an option of `app` that stores into
/// `value`: the same value (--help lists it in its own group); once the command line has
/// parsed, tell_old_spellings() names the new spelling on standard error. Giving both is a
/// command-line error. Returns the old spelling's option (for the program's own excludes).
template <class T>
CLI::Option* accept_old_spelling(CLI::App& app, CLI::Option* current, const std::string& old_name, T& value) {
  // In its own --help group, its description the new spelling.
  CLI::Option* old = app.add_option(old_name, value, "use " + current->get_name())->group(kOldSpellings);
  old->excludes(current);
  return old;
}

/// After a successful parse: one line on stderr per old spelling given (accept_old_spelling()).
inline void tell_old_spellings(const CLI::App& app) {
  for (const CLI::Option* o : app.get_options())
    if (o->get_group() == kOldSpellings && o->count() > 0)
      std::fprintf(stderr, "%s is deprecated and goes in adaptseg 0.4: %s\n", o->get_name().c_str(),
                   o->get_description().c_str());
}

}  // namespace adaptseg::examples
