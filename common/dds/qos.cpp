#include "common/dds/qos.hpp"

namespace qswarm {

namespace dds = eprosima::fastdds::dds;

namespace {
// Each reliable write to a remote reader restarts that reader's nack-suppression timer, and in
// Fast DDS 2.9.1 restarting an idle timer wakes the participant's event thread: with the default
// (none) that is one wake-up per record. Suppressing NACKs for longer than a record period keeps
// the timer running from one write to the next, so it wakes about twice a second instead. A NACK
// it ignores asks for the one sample in the history, which the next record replaces anyway.
const eprosima::fastrtps::Duration_t kRecordNackSuppression{1, 0};

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
  q.reliable_writer_qos().times.nackSupressionDuration = kRecordNackSuppression;
  return q;
}

dds::DataReaderQos record_reader_qos() {
  dds::DataReaderQos q = best_effort_reader_qos(1);
  q.reliability().kind = dds::RELIABLE_RELIABILITY_QOS;
  return q;
}

}  // namespace qswarm
