#include "common/dds/qos.hpp"

namespace qswarm {

namespace dds = eprosima::fastdds::dds;

dds::DataWriterQos best_effort_writer_qos(int depth) {
  dds::DataWriterQos q = dds::DATAWRITER_QOS_DEFAULT;
  q.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
  q.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  q.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = depth;
  q.data_sharing().off();
  return q;
}

dds::DataReaderQos best_effort_reader_qos(int depth) {
  dds::DataReaderQos q = dds::DATAREADER_QOS_DEFAULT;
  q.reliability().kind = dds::BEST_EFFORT_RELIABILITY_QOS;
  q.durability().kind = dds::VOLATILE_DURABILITY_QOS;
  q.history().kind = dds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = depth;
  q.data_sharing().off();
  return q;
}

}  // namespace qswarm
