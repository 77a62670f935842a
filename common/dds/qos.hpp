#pragma once

#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

namespace qswarm {

// Every endpoint of the project publishes state that the next sample replaces: best-effort (a
// reliable writer's 3 s default heartbeat would stall a lost sample for seconds), volatile, keep
// the last `depth`, and no data-sharing (it would bypass the transports the faults act on).
eprosima::fastdds::dds::DataWriterQos best_effort_writer_qos(int depth = 1);
eprosima::fastdds::dds::DataReaderQos best_effort_reader_qos(int depth = 1);

}  // namespace qswarm
