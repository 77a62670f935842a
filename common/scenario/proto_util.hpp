#pragma once

#include <google/protobuf/message.h>
#include <google/protobuf/repeated_field.h>
#include <google/protobuf/util/json_util.h>

#include <string>

#include "common/core/math.hpp"

namespace qswarm {

// A vector as three repeated doubles (x, y, z), as the record's messages store positions.
inline void put_vec3(google::protobuf::RepeatedField<double>* f, const Vec3& v) {
  f->Add(v.x());
  f->Add(v.y());
  f->Add(v.z());
}

// The JSON the project writes for people and programs (summary.json, inspect --json): indented,
// the proto's field names, every field present.
inline std::string to_json(const google::protobuf::Message& m) {
  std::string json;
  google::protobuf::util::JsonPrintOptions opt;
  opt.add_whitespace = true;
  opt.preserve_proto_field_names = true;
  opt.always_print_primitive_fields = true;
  (void)google::protobuf::util::MessageToJsonString(m, &json, opt);
  return json;
}

}  // namespace qswarm
