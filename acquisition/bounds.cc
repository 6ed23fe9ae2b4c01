#include "acquisition/bounds.h"

#include <cmath>
#include <cstdio>

namespace gf {

std::string FormatNumber(double value) {
  char text[32];
  // Whole numbers of up to ten digits in full (counts and sizes: 357913941, not 3.57914e+08).
  if (value == std::floor(value) && std::abs(value) < 1e10)
    std::snprintf(text, sizeof(text), "%.0f", value);
  else
    std::snprintf(text, sizeof(text), "%g", value);
  return text;
}

void FieldCheck::Refuse(const std::string& problem) {
  ok_ = false;
  if (message_) *message_ = problem;
}

FieldCheck& FieldCheck::In(const char* field, double value, double low, double high,
                           const char* beyond) {
  if (!ok_) return *this;
  const std::string name = std::string(field) + " " + FormatNumber(value);
  if (std::isnan(value))
    Refuse(std::string(field) + " is not a number");
  else if (value < low)
    Refuse(name + " must be at least " + FormatNumber(low));
  else if (value > high)
    Refuse(name + " " + beyond + " (at most " + FormatNumber(high) + ")");
  return *this;
}

FieldCheck& FieldCheck::Above(const char* field, double value, double low, double high,
                              const char* beyond) {
  if (!ok_) return *this;
  if (!std::isnan(value) && value <= low)
    Refuse(std::string(field) + " " + FormatNumber(value) + " must be more than " +
           FormatNumber(low));
  return In(field, value, low, high, beyond);
}

FieldCheck& FieldCheck::Each(const char* field, const std::vector<int>& values, int low, int high,
                             const char* beyond) {
  if (!ok_) return *this;
  if (values.empty()) Refuse(std::string(field) + " must list at least one value");
  for (size_t i = 0; i < values.size() && ok_; ++i)
    In((std::string(field) + "[" + std::to_string(i) + "]").c_str(), values[i], low, high, beyond);
  return *this;
}

FieldCheck& FieldCheck::Require(bool condition, const std::string& problem) {
  if (ok_ && !condition) Refuse(problem);
  return *this;
}

}  // namespace gf
