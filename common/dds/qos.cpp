#include "common/dds/qos.hpp"

namespace qswarm {

namespace dds = eprosima::fastdds::dds;

namespace {
// Writer and reader take the same settings through the same accessors.
template <typename Qos>
Qos best_effort(Qos q, int depth) {
  q.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
  q.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  q.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = depth;
  q.data_sharing().off();
  return q;
}
}  // namespace

dds::DataWriterQos best_effort_writer_qos(int depth) {
  return best_effort(dds::DATAWRITER_QOS_DEFAULT, depth);
}

dds::DataReaderQos best_effort_reader_qos(int depth) {
  return best_effort(dds::DATAREADER_QOS_DEFAULT, depth);
}

dds::DataWriterQos record_writer_qos() {
  dds::DataWriterQos q = best_effort_writer_qos(1);
  q.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  q.resource_limits().max_instances = 1;
  q.resource_limits().max_samples_per_instance = 1;
  q.resource_limits().max_samples = 1;
  return q;
}

dds::DataReaderQos record_reader_qos() {
  dds::DataReaderQos q = best_effort_reader_qos(1);
  q.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  return q;
}

}  // namespace qswarm
