#include "common/dds/discovery_server.hpp"

#include <fastdds/rtps/attributes/ServerAttributes.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>

#include <atomic>
#include <stdexcept>

#include "common/dds/participant.hpp"
#include "common/transport/port_plan.hpp"

namespace qswarm {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastdds::rtps;

struct DiscoveryServer::Impl : public dds::DomainParticipantListener {
  dds::DomainParticipant* participant = nullptr;
  std::atomic<int> clients{0};
  void on_participant_discovery(
      dds::DomainParticipant*, eprosima::fastrtps::rtps::ParticipantDiscoveryInfo&& info) override {
    using Status = eprosima::fastrtps::rtps::ParticipantDiscoveryInfo::DISCOVERY_STATUS;
    if (info.status == Status::DISCOVERED_PARTICIPANT) ++clients;
    if (info.status == Status::REMOVED_PARTICIPANT || info.status == Status::DROPPED_PARTICIPANT)
      --clients;
  }
};

DiscoveryServer::DiscoveryServer(std::uint32_t domain_id, const std::string& listen,
                                 std::uint16_t port, int participant_id, int index,
                                 const std::vector<std::pair<std::string, std::uint16_t>>& servers)
    : impl_(std::make_unique<Impl>()) {
  address_ = resolve_discovery_server(listen + ":" + std::to_string(port)).first;
  dds::DomainParticipantQos pqos;
  pqos.name("swarm-discovery");
  pqos.transport().use_builtin_transports = false;
  auto udp = std::make_shared<rtps::UDPv4TransportDescriptor>();
  // Only the interface it listens on: without this Fast DDS binds its sockets to every address
  // (a stranger on another network could reach the server) and opens an output socket on each
  // interface. An agent's participant is confined the same way (participant.cpp). An address no
  // interface holds (a host name that resolves to 127.0.1.1, as Debian's /etc/hosts has it) would
  // leave Fast DDS no interface at all: the server then listens everywhere, as it did before.
  if (local_ipv4_addresses().count(address_)) udp->interfaceWhiteList.push_back(address_);
  pqos.transport().user_transports.push_back(udp);
  // The project's port plan, as every participant of the swarm uses it.
  pqos.wire_protocol().port.portBase = PortPlan::kBase;
  pqos.wire_protocol().port.domainIDGain = PortPlan::kDomainGain;
  pqos.wire_protocol().port.participantIDGain = PortPlan::kParticipantGain;
  if (participant_id >= 0) {
    // The run reserved this id's ports for its server: take exactly them, and say if one is taken
    // rather than come up on shifted ports.
    if (const std::string problem = participant_ports_problem(domain_id, participant_id, address_);
        !problem.empty())
      throw std::runtime_error(problem);
    pqos.wire_protocol().participant_id = participant_id;
    pqos.wire_protocol().builtin.mutation_tries = 0;
  }
  disable_writer_liveliness(pqos);
  auto& disc = pqos.wire_protocol().builtin.discovery_config;
  disc.discoveryProtocol = eprosima::fastrtps::rtps::DiscoveryProtocol_t::SERVER;
  // An infinite lease, as every DdsBus participant announces: no client runs a lease check on the
  // server, the check that races the server's removal when it leaves (participant.cpp says more).
  disc.leaseDuration = eprosima::fastrtps::c_TimeInfinite;
  // Nor does it announce itself on a timer. Fast DDS 2.9.1's periodic announcement of a server is
  // sent straight to every client its database holds, and a client that has just arrived can be
  // there before its locators have an output channel: the UDP transport's statistics then assert
  // (OutputTrafficManager.hpp:87) and the server aborts. Clients need no such refresh: the lease
  // is infinite, and a client gets the server's DATA(p) from the server's reliable PDP writer once
  // matched (docs/fast-dds-workarounds.md, W3).
  disc.initial_announcements.count = 0;
  disc.leaseDuration_announcementperiod = eprosima::fastrtps::Duration_t(kNeverSeconds, 0);
  rtps::get_server_client_default_guidPrefix(index, pqos.wire_protocol().prefix);
  add_discovery_servers(servers, index, disc.m_DiscoveryServers);
  eprosima::fastrtps::rtps::Locator_t loc;
  eprosima::fastrtps::rtps::IPLocator::setIPv4(loc, address_);
  loc.port = port;
  pqos.wire_protocol().builtin.metatrafficUnicastLocatorList.push_back(loc);
  impl_->participant = dds::DomainParticipantFactory::get_instance()->create_participant(
      domain_id, pqos, impl_.get(), dds::StatusMask::none());
  if (!impl_->participant)
    throw std::runtime_error("cannot start a discovery server on " + address_ + ":" +
                             std::to_string(port));
}

DiscoveryServer::~DiscoveryServer() {
  if (impl_->participant) {
    impl_->participant->set_listener(nullptr);
    dds::DomainParticipantFactory::get_instance()->delete_participant(impl_->participant);
  }
}

int DiscoveryServer::clients() const { return impl_->clients; }

DiscoveryServer::Announcements DiscoveryServer::announcements() const {
  const auto qos = impl_->participant->get_qos();
  const auto& disc = qos.wire_protocol().builtin.discovery_config;
  return {disc.initial_announcements.count,
          static_cast<double>(disc.leaseDuration_announcementperiod.seconds)};
}

}  // namespace qswarm
