#include "physgrad/io/serialize.hpp"

#include <climits>
#include <cmath>

#include "physgrad/error.hpp"

namespace physgrad {

namespace {

[[noreturn]] void bad_field(const std::string& key, const std::string& problem) {
  throw Error("checkpoint field '" + key + "': " + problem);
}

const nlohmann::json& field(const nlohmann::json& document, const std::string& key) {
  if (!document.is_object()) bad_field(key, "the enclosing value is not an object");
  const auto found = document.find(key);
  if (found == document.end()) bad_field(key, "missing");
  return *found;
}

}  // namespace

nlohmann::json vector_to_json(const Vector& v) {
  nlohmann::json array = nlohmann::json::array();
  for (Index i = 0; i < v.size(); ++i) array.push_back(v[i]);
  return array;
}

Vector vector_from_json(const nlohmann::json& document, const std::string& key,
                        Index expected_size) {
  const nlohmann::json& array = field(document, key);
  if (!array.is_array()) bad_field(key, "expected an array of numbers, got " + std::string(array.type_name()));
  const auto size = static_cast<Index>(array.size());
  if (expected_size >= 0 && size != expected_size) {
    bad_field(key, "has " + std::to_string(size) + " values, expected " +
                       std::to_string(expected_size));
  }
  Vector v(size);
  for (Index i = 0; i < size; ++i) {
    const nlohmann::json& value = array[static_cast<std::size_t>(i)];
    if (!value.is_number()) bad_field(key, "entry " + std::to_string(i) + " is not a number");
    v[i] = value.get<double>();
    if (!std::isfinite(v[i])) bad_field(key, "entry " + std::to_string(i) + " is not finite");
  }
  return v;
}

double real_from_json(const nlohmann::json& document, const std::string& key, bool null_is_nan) {
  const nlohmann::json& value = field(document, key);
  if (null_is_nan && value.is_null()) return NAN;
  if (!value.is_number()) bad_field(key, "expected a number, got " + std::string(value.type_name()));
  return value.get<double>();
}

long long integer_from_json(const nlohmann::json& document, const std::string& key,
                            long long min) {
  const nlohmann::json& value = field(document, key);
  if (!value.is_number_integer()) {
    bad_field(key, "expected an integer, got " + std::string(value.type_name()));
  }
  if (value.is_number_unsigned() &&
      value.get<unsigned long long>() > static_cast<unsigned long long>(LLONG_MAX)) {
    bad_field(key, "integer out of range");
  }
  const long long n = value.get<long long>();
  if (n < min) bad_field(key, "must be ≥ " + std::to_string(min) + ", got " + std::to_string(n));
  return n;
}

const nlohmann::json& object_from_json(const nlohmann::json& document, const std::string& key) {
  const nlohmann::json& value = field(document, key);
  if (!value.is_object()) bad_field(key, "expected an object, got " + std::string(value.type_name()));
  return value;
}

std::string string_from_json(const nlohmann::json& document, const std::string& key) {
  const nlohmann::json& value = field(document, key);
  if (!value.is_string()) bad_field(key, "expected a string, got " + std::string(value.type_name()));
  return value.get<std::string>();
}

}  // namespace physgrad
