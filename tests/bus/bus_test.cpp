#include "tachi/bus/topics.hpp"
#include <gtest/gtest.h>
using namespace tachi;
TEST(Bus, Smoke) {
  bus::Participant p{11};
  bus::Writer<tachi_msg_RawHandSample> w{p, bus::topics::raw_hand};
  bus::Reader<tachi_msg_RawHandSample> r{p, bus::topics::raw_hand};
  ASSERT_TRUE(w.wait_for_readers(1, std::chrono::seconds(5)));
  tachi_msg_RawHandSample s{};
  s.sensor_id = 3; s.frame = 42;
  w.write(s);
  ASSERT_TRUE(r.wait_for_data(std::chrono::seconds(2)));
  auto got = r.take();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0]->frame, 42u);
}
