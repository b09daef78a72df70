// JSON form of numeric state (parameters, optimizer moments, training records) for
// checkpoints. Doubles are written in their shortest round-trip form, so a value read back is
// bit-identical to the one written. Readers validate and throw Error naming the field.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "physgrad/types.hpp"

namespace physgrad {

nlohmann::json vector_to_json(const Vector& v);

// The array at document[key] as a Vector of finite values; `expected_size` ≥ 0 also checks the
// length. Throws Error "checkpoint field 'KEY': …" when missing, not an array of numbers,
// non-finite or of the wrong length.
Vector vector_from_json(const nlohmann::json& document, const std::string& key,
                        Index expected_size = -1);
// document[key] as a number (null reads as NaN when `null_is_nan`), or as an integer ≥ `min`.
double real_from_json(const nlohmann::json& document, const std::string& key,
                      bool null_is_nan = false);
long long integer_from_json(const nlohmann::json& document, const std::string& key,
                            long long min = 0);
// document[key] as an object (or a string); throws when missing or of another type.
const nlohmann::json& object_from_json(const nlohmann::json& document, const std::string& key);
std::string string_from_json(const nlohmann::json& document, const std::string& key);

}  // namespace physgrad
