#include <gtest/gtest.h>

#include "drivers/link_uri.hpp"

using drivers::LinkErrorKind;
using drivers::LinkScheme;
using drivers::parse_link_uri;

TEST(LinkUri, ModbusTcp) {
  auto u = parse_link_uri("modbus+tcp://127.0.0.1:1502?unit=7");
  ASSERT_TRUE(u) << u.error().message();
  EXPECT_EQ(u->scheme, LinkScheme::kModbusTcp);
  EXPECT_EQ(u->host, "127.0.0.1");
  EXPECT_EQ(u->port, 1502);
  EXPECT_EQ(u->unit, 7);
  EXPECT_TRUE(u->is_modbus());
}

TEST(LinkUri, ModbusRtuWithSerialSettings) {
  auto u = parse_link_uri("modbus+rtu:/dev/ttyUSB0?baud=9600&unit=3&parity=E&data=7&stop=2");
  ASSERT_TRUE(u) << u.error().message();
  EXPECT_EQ(u->scheme, LinkScheme::kModbusRtu);
  EXPECT_EQ(u->device, "/dev/ttyUSB0");
  EXPECT_EQ(u->baud, 9600);
  EXPECT_EQ(u->unit, 3);
  EXPECT_EQ(u->parity, 'E');
  EXPECT_EQ(u->data_bits, 7);
  EXPECT_EQ(u->stop_bits, 2);
  auto d = parse_link_uri("modbus+rtu:/dev/ttyS1");
  ASSERT_TRUE(d);
  EXPECT_EQ(d->baud, 19200);
  EXPECT_EQ(d->parity, 'N');
  EXPECT_EQ(d->unit, 1);
}

TEST(LinkUri, CanForms) {
  auto s = parse_link_uri("can+socketcan:can0");
  ASSERT_TRUE(s);
  EXPECT_EQ(s->scheme, LinkScheme::kCanSocketcan);
  EXPECT_EQ(s->device, "can0");
  auto u = parse_link_uri("can+udp://127.0.0.1:29536");
  ASSERT_TRUE(u);
  EXPECT_EQ(u->scheme, LinkScheme::kCanUdp);
  EXPECT_EQ(u->port, 29536);
  EXPECT_TRUE(u->is_can());
}

TEST(LinkUri, CanTsc1Command) {
  auto u = parse_link_uri("can+udp://127.0.0.1:29536?command=tsc1&sync_rpm=600");
  ASSERT_TRUE(u) << u.error().message();
  EXPECT_EQ(u->can_command, drivers::CanCommand::kTsc1);
  EXPECT_DOUBLE_EQ(u->sync_rpm, 600.0);
  EXPECT_EQ(parse_link_uri("can+socketcan:can0")->can_command, drivers::CanCommand::kBiasFrame);
}

TEST(LinkUri, DefaultFamilyForPlantsimOptions) {
  auto m = parse_link_uri("tcp://127.0.0.1:1502", "modbus");
  ASSERT_TRUE(m);
  EXPECT_EQ(m->scheme, LinkScheme::kModbusTcp);
  EXPECT_EQ(m->text, "modbus+tcp://127.0.0.1:1502");
  auto c = parse_link_uri("socketcan:vcan0", "can");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->scheme, LinkScheme::kCanSocketcan);
  EXPECT_EQ(c->device, "vcan0");
}

namespace {
void expect_error(const char* uri, const char* part, const char* expected_text) {
  auto u = parse_link_uri(uri);
  ASSERT_FALSE(u) << uri;
  EXPECT_EQ(u.error().kind, LinkErrorKind::kConfig);
  EXPECT_NE(u.error().where.find(part), std::string::npos) << u.error().message();
  EXPECT_NE(u.error().detail.find(expected_text), std::string::npos) << u.error().message();
}
}  // namespace

TEST(LinkUri, ErrorsNameThePartAndWhatWasExpected) {
  expect_error("127.0.0.1:1502", "scheme", "expected modbus+tcp");
  expect_error("serial", "scheme", "expected '<scheme>:'");
  expect_error("modbus+udp://h:1", "scheme", "got 'modbus+udp'");
  expect_error("modbus+tcp:127.0.0.1:1502", "authority", "//host:port");
  expect_error("modbus+tcp://127.0.0.1", "authority", "host:port");
  expect_error("modbus+tcp://127.0.0.1:99999", "port", "0..65535");
  expect_error("modbus+tcp://:1502", "host", "host name");
  expect_error("modbus+tcp://h:1502?unit=300", "query 'unit=300'", "0..247");
  expect_error("modbus+tcp://h:1502?baud=9600", "query 'baud=9600'", "expected unit");
  expect_error("modbus+rtu:/dev/ttyUSB0?baud=fast", "query 'baud=fast'", "baud rate");
  expect_error("modbus+rtu:/dev/ttyUSB0?parity=X", "query 'parity=X'", "N, E or O");
  expect_error("modbus+rtu:?baud=9600", "device", "serial device");
  expect_error("can+socketcan:", "device", "CAN interface");
  expect_error("can+udp://127.0.0.1:29536?unit=1", "query 'unit=1'", "unknown key");
  expect_error("can+socketcan:can0?command=tsc1", "query", "sync_rpm=<rpm>");
  expect_error("can+socketcan:can0?command=speed", "query 'command=speed'", "ff50 or tsc1");
  expect_error("can+socketcan:can0?sync_rpm=-5", "query 'sync_rpm=-5'", "positive speed");
  expect_error("modbus+tcp://h:1?command=tsc1", "query 'command=tsc1'", "expected unit");
}
