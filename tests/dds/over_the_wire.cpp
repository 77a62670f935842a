// The product runs one participant per process; these tests run several in one. Fast DDS would
// hand samples and discovery between participants of one process without their transport, and
// a transport's faults (the test transport's drops) would never bite: every participant of this
// binary talks over its transport, as separate processes do.
#include <fastrtps/attributes/LibrarySettingsAttributes.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <gtest/gtest.h>

namespace {

class OverTheWire : public ::testing::Environment {
 public:
  void SetUp() override {
    eprosima::fastrtps::LibrarySettingsAttributes s;
    s.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
    eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(s);
  }
};

[[maybe_unused]] const ::testing::Environment* const kOverTheWire =
    ::testing::AddGlobalTestEnvironment(new OverTheWire);

}  // namespace
