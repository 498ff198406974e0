// `drivegate dcmd` end to end: a Sparkplug command from the command line, through a real
// mosquitto, to the real daemon's edge node and a simulated drive of the tests' own (test-drive),
// and the result the edge node publishes printed back. The broker, group and edge node ids come
// from the daemon's own configuration file. The DCMD on the wire is read by the independent peer
// (Eclipse Tahu's decoder, sparkplug_peer.h), not by drivegate's codec; the drive's answer by the
// PLC's registers and the simulator.
#include "mqtt_e2e.h"

namespace drivegate::test {
namespace {

using ::testing::HasSubstr;

struct ToolRun {
  int status;
  std::string out;  // stdout
  std::string err;  // stderr
};

class DcmdE2E : public MqttE2E {
 protected:
  // `drivegate dcmd` with `args` after the command, to its end.
  ToolRun dcmd(std::vector<std::string> args, const fs::path& config = {}) {
    std::vector<std::string> argv = {(bin_dir() / "drivegate").string(),
                                     "dcmd",
                                     "--config",
                                     (config.empty() ? daemon_->config() : config).string(),
                                     "--plugin-dir",
                                     plugin_dir().string()};
    argv.insert(argv.end(), args.begin(), args.end());
    Child c(argv, dir_ / "dcmd.err");
    std::string out;
    while (auto line = c.read_line(20s)) out += *line + "\n";
    const int status = c.wait_exit(20s);
    return {status, out, slurp(dir_ / "dcmd.err")};
  }
};

TEST_F(DcmdE2E, ACommandFromTheToolRunsTheDriveAndItsResultIsPrinted) {
  start_daemon("commands = true\n");
  wait_births();
  ASSERT_FALSE(HasFailure());

  // A setpoint and a run by its label, one command: ok once the drive confirmed it.
  const auto run = dcmd({"--device", "drive-a", "setpoint_rpm=600", "command=run_forward"});
  EXPECT_EQ(run.status, 0) << run.out << run.err;
  EXPECT_EQ(run.out, "drive-a: setpoint_rpm,command: ok\n") << run.err;
  EXPECT_TRUE(eventually([&] { return speed(1) == 600; }, 10s))
      << drive("drive-a").sim->control("state");
  EXPECT_EQ(holding(1, reg::command), 1);
  // What went on the wire, as Tahu reads it: a DCMD for drive-a with the two metrics, typed.
  const auto sent = peer_->wait_for([](const Message& m) { return is(m, "DCMD", "drive-a"); }, 1s);
  ASSERT_TRUE(sent.has_value()) << describe(peer_->history());
  ASSERT_EQ(sent->metrics.size(), 2u) << describe(*sent);
  EXPECT_EQ(sent->metrics[0].name, "setpoint_rpm");
  EXPECT_EQ(sent->metrics[0].type, "Int64");
  EXPECT_EQ(sent->metrics[0].value, "600");
  EXPECT_EQ(sent->metrics[1].name, "command");
  EXPECT_EQ(sent->metrics[1].value, "1");
  EXPECT_FALSE(sent->retain);

  // The edge node's refusals are printed as it words them, exit status 1: a value the point
  // cannot hold, a metric it does not have.
  const auto too_fast = dcmd({"-d", "drive-a", "setpoint_rpm=70000"});
  EXPECT_EQ(too_fast.status, 1);
  EXPECT_EQ(too_fast.out, "drive-a: setpoint_rpm: exception 0x03 (illegal data value)\n")
      << too_fast.err;
  const auto unknown = dcmd({"-d", "drive-a", "nonsense=1"});
  EXPECT_EQ(unknown.status, 1);
  EXPECT_EQ(unknown.out, "drive-a: nonsense: refused: no metric 'nonsense'\n") << unknown.err;
  // Neither changed the drive; a stop by label does.
  EXPECT_EQ(speed(1), 600);
  EXPECT_EQ(dcmd({"-d", "drive-a", "command=stop"}).out, "drive-a: command: ok\n");
  EXPECT_TRUE(eventually([&] { return holding(1, reg::command) == 0; }, 5s));
  EXPECT_THAT(daemon_log(), HasSubstr("MQTT: DCMD drive-a setpoint_rpm,command"));
}

// What the tool can tell before it sends anything, it tells: a value that is no number, boolean
// or label of the point; a device the file does not have; a file whose edge node takes no
// commands. And what it cannot: a device that is not born answers nothing, which is a timeout
// naming where it asked.
TEST_F(DcmdE2E, WhatCannotBeSentOrAnsweredIsSaid) {
  start_daemon("commands = true\n");
  wait_births();
  ASSERT_FALSE(HasFailure());
  const auto label = dcmd({"-d", "drive-a", "command=sideways"});
  EXPECT_EQ(label.status, 1);
  EXPECT_THAT(label.err, HasSubstr("command: 'sideways' is not a number, true or false or a "
                                   "label of the point"));
  const auto device = dcmd({"-d", "drive-z", "command=stop"});
  EXPECT_EQ(device.status, 1);
  EXPECT_THAT(device.err, HasSubstr("no device 'drive-z' in " + daemon_->config().string()));

  std::ofstream(dir_ / "off.toml") << config("commands = false\n");
  const auto off = dcmd({"-d", "drive-a", "command=stop"}, dir_ / "off.toml");
  EXPECT_EQ(off.status, 1);
  EXPECT_THAT(off.err, HasSubstr("says [mqtt] commands = false: the edge node refuses every DCMD"));

  drive("drive-b").sim->control("silent on");
  ASSERT_TRUE(wait("DDEATH", "drive-b", 10s).has_value());
  const auto dead = dcmd({"-d", "drive-b", "-t", "1500", "command=stop"});
  EXPECT_EQ(dead.status, 1);
  EXPECT_EQ(dead.out, "");
  EXPECT_THAT(dead.err, HasSubstr("drive-b: command: no result within 1500 ms from edge node "
                                  "plant1/gw01 on " +
                                  broker_->url() +
                                  ": is drivegated connected to this broker, the device born"));
  EXPECT_THAT(dead.err, HasSubstr(", the edge node born there (with a primary_host, that host "
                                  "online), "));
}

// A broker that is not there: each of [mqtt] brokers is tried, and the refusal says which.
TEST_F(DcmdE2E, ABrokerThatIsNotThereIsNamed) {
  start_daemon("commands = true\n");
  const std::string nobody = "mqtt://127.0.0.1:" + std::to_string(free_port());
  std::string text = slurp(daemon_->config());
  text.replace(text.find(broker_->url()), broker_->url().size(), nobody);
  std::ofstream(dir_ / "gone.toml") << text;
  const auto r = dcmd({"-d", "drive-a", "-t", "3000", "command=stop"}, dir_ / "gone.toml");
  EXPECT_EQ(r.status, 1);
  EXPECT_THAT(r.err, HasSubstr("cannot reach the broker: " + nobody + ": "));
  EXPECT_EQ(holding(1, reg::command), 0);
}

}  // namespace
}  // namespace drivegate::test
