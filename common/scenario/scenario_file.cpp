// Scenario files: Protobuf text in, Protobuf text out; syntax errors name the line and column.
#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include "common/scenario/scenario.hpp"
#include "common/transport/regular_file.hpp"

namespace qswarm {
namespace {

class Collector : public google::protobuf::io::ErrorCollector {
 public:
  explicit Collector(std::string source) : source_(std::move(source)) {}
  void AddError(int line, google::protobuf::io::ColumnNumber col, const std::string& msg) override {
    if (first_.empty()) {
      first_ =
          source_ + ":" + std::to_string(line + 1) + ":" + std::to_string(col + 1) + ": " + msg;
    }
  }
  void AddWarning(int, google::protobuf::io::ColumnNumber, const std::string&) override {}
  const std::string& first() const { return first_; }

 private:
  std::string source_;
  std::string first_;
};

}  // namespace

scenario::Scenario parse_scenario_text(const std::string& text, const std::string& source) {
  scenario::Scenario s;
  google::protobuf::TextFormat::Parser parser;
  Collector errors(source);
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(text, &s)) {
    throw ScenarioError(errors.first().empty() ? source + ": not a valid scenario"
                                               : errors.first());
  }
  return s;
}

scenario::Scenario read_scenario_file(const std::string& path) {
  // A FIFO, a device or a huge file is refused before reading: /dev/zero would never end.
  RegularFile f;
  const std::string text = read_regular_file(path, kMaxScenarioBytes, f);
  switch (f.problem) {
    case RegularFile::Problem::kNone:
      return parse_scenario_text(text, path);
    case RegularFile::Problem::kMissing:
      throw ScenarioError(path + ": no such scenario file");
    case RegularFile::Problem::kNotRegular:
      throw ScenarioError(path + ": expected a regular file (a scenario in Protobuf text format)");
    case RegularFile::Problem::kTooLarge:
      throw ScenarioError(path + ": expected a scenario of at most " +
                          std::to_string(kMaxScenarioBytes / 1024) + " KiB");
    case RegularFile::Problem::kUnreadable:
      break;
  }
  throw ScenarioError(path + ": " + f.why);
}

std::string to_text(const scenario::Scenario& s) {
  std::string out;
  google::protobuf::TextFormat::Printer printer;
  printer.PrintToString(s, &out);
  return out;
}

RunConfig load_scenario(const std::string& path, const ScenarioOverrides& o) {
  return resolve_scenario(read_scenario_file(path), o);
}

}  // namespace qswarm
