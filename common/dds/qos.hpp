#pragma once

#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

namespace qswarm {

// Endpoints publish state that the next sample replaces: best-effort by default (a
// reliable writer's 3 s default heartbeat would stall a lost sample for seconds), volatile, keep
// the last `depth`, and no data-sharing (it would bypass the transports the faults act on).
eprosima::fastdds::dds::DataWriterQos best_effort_writer_qos(int depth = 1);
eprosima::fastdds::dds::DataReaderQos best_effort_reader_qos(int depth = 1);

// The record stream (agent to supervisor) is reliable instead, so that an agent can know the
// supervisor hears it: only a reader that matched the writer acknowledges its samples. The
// writer's history holds the one newest sample of the agent's one key, so it is full after every
// write and every sample carries a heartbeat: the supervisor acknowledges at once, and a lost
// sample is answered with a gap (the newer sample replaced it) within a round trip, not at the
// 3 s heartbeat period. Keep-last: a slow or stopped recorder never blocks the agent.
eprosima::fastdds::dds::DataWriterQos record_writer_qos();
eprosima::fastdds::dds::DataReaderQos record_reader_qos();

}  // namespace qswarm
