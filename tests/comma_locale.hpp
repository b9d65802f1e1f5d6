#pragma once
// A global locale whose decimal separator is a comma and that groups thousands, set for the
// lifetime of a CommaLocale and restored after: files must be written and read the same under
// it. Built from the classic locale, so no system locale needs to be installed.

#include <locale>
#include <string>

namespace adaptseg::test {

class CommaLocale {
 public:
  CommaLocale() : previous_(std::locale::global(std::locale(std::locale::classic(), new Comma))) {}
  ~CommaLocale() { std::locale::global(previous_); }
  CommaLocale(const CommaLocale&) = delete;
  CommaLocale& operator=(const CommaLocale&) = delete;

 private:
  struct Comma : std::numpunct<char> {
    char do_decimal_point() const override { return ','; }
    char do_thousands_sep() const override { return '.'; }
    std::string do_grouping() const override { return "\3"; }
  };
  std::locale previous_;
};

}  // namespace adaptseg::test
