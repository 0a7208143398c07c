// The JSON schemas of schemas/, compiled into the binary.
#pragma once

#include <string_view>
#include <vector>

namespace hfbake {

struct EmbeddedSchema {
  std::string_view path;  // relative to schemas/, e.g. "job.schema.json", "methods/p1.schema.json"
  std::string_view text;
};

const std::vector<EmbeddedSchema>& embedded_schemas();

}  // namespace hfbake
