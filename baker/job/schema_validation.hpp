// JSON-schema validation (valijson) against hfbake's embedded schemas, reported as one line per violation.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hfbake {

struct SchemaViolation {
  std::string pointer;  // JSON pointer of the offending value, e.g. "/bake/0/directions" ("" = the root)
  std::string message;  // e.g. "must be >= 1", "unknown key", "missing required key \"name\""
};

// Validates `doc` against the embedded schema `schema_path` (e.g. "job.schema.json"). Returns the leaf
// violations (not the chain of enclosing "failed to validate item" messages), in document order.
std::vector<SchemaViolation> validate_against_schema(const nlohmann::json& doc,
                                                     const std::string& schema_path);

}  // namespace hfbake
