// bench_bag_writer: the tools' own bag writer (src/tools/bag_writer.h, BagOutput) against
// rosbag::Bag::write, the reason given for having the former. Both write the same MESSAGES
// sensor_msgs/Imu messages (a 200 Hz stream, uncompressed, one topic) to a new file in DIR, open
// to close; the two alternate for ROUNDS rounds (the order swapped every round, so that a burst
// of load from another process or the page cache's writeback hits both alike) and the median of
// each is reported: wall time, CPU time (user + system of the process) and the system time
// within it (rosbag's cost is in system calls). Each file is removed after its run.
// Usage: bench_bag_writer [ROUNDS] [MESSAGES] [DIR]   (defaults 5, 400000, /tmp)
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>

#include "../src/tools/bag_writer.h"

namespace {

namespace tools = attitude_propagator::tools;

constexpr double kRateHz = 200.0;
const char* const kTopic = "/imu/data";

/// The k-th message of the stream: a coning motion's body rates, gravity, no orientation.
sensor_msgs::Imu imuMessage(std::size_t k, ros::Time* stamp) {
  const double t = static_cast<double>(k) / kRateHz;
  *stamp = ros::Time(1700000000) + ros::Duration(t);
  sensor_msgs::Imu msg;
  msg.header.seq = static_cast<std::uint32_t>(k);
  msg.header.stamp = *stamp;
  msg.header.frame_id = "imu_link";
  msg.orientation_covariance[0] = -1.0;
  msg.angular_velocity.x = -0.01;
  msg.angular_velocity.y = -0.7 * std::sin(6.9 * t);
  msg.angular_velocity.z = 0.7 * std::cos(6.9 * t);
  msg.linear_acceleration.z = 9.81;
  return msg;
}

struct Times {
  double wall_s, cpu_s, system_s;
};

/// The process's CPU time so far, user + system, and the system part.
Times cpuSeconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& tv) {
    return static_cast<double>(tv.tv_sec) + 1e-6 * static_cast<double>(tv.tv_usec);
  };
  return {0.0, seconds(usage.ru_utime) + seconds(usage.ru_stime), seconds(usage.ru_stime)};
}

template <class Write>
Times timed(const std::string& path, Write write) {
  std::remove(path.c_str());
  const Times before = cpuSeconds();
  const auto start = std::chrono::steady_clock::now();
  write(path);
  const std::chrono::duration<double> wall = std::chrono::steady_clock::now() - start;
  const Times after = cpuSeconds();
  const Times times{wall.count(), after.cpu_s - before.cpu_s, after.system_s - before.system_s};
  std::remove(path.c_str());
  return times;
}

void writeWithRosbag(const std::string& path, std::size_t messages) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);  // uncompressed, rosbag's default
  ros::Time stamp;
  for (std::size_t k = 0; k < messages; ++k) {
    const sensor_msgs::Imu msg = imuMessage(k, &stamp);
    bag.write(kTopic, stamp, msg);
  }
  bag.close();
}

void writeWithBagOutput(const std::string& path, std::size_t messages) {
  tools::BagOutput bag(path, path, tools::BagOutput::Compression::None);
  ros::Time stamp;
  for (std::size_t k = 0; k < messages; ++k) {
    const sensor_msgs::Imu msg = imuMessage(k, &stamp);
    bag.write(kTopic, stamp, msg);
  }
  bag.close();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  const int rounds = argc > 1 ? std::atoi(argv[1]) : 5;
  const std::size_t messages = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 400000;
  const std::string dir = argc > 3 ? argv[3] : "/tmp";
  if (rounds < 1 || messages < 1) {
    std::fprintf(stderr, "usage: bench_bag_writer [ROUNDS] [MESSAGES] [DIR]\n");
    return 2;
  }
  const std::string rosbag_path = dir + "/bench_bag_writer_rosbag.bag";
  const std::string own_path = dir + "/bench_bag_writer_own.bag";
  const auto rosbag = [&](const std::string& path) { writeWithRosbag(path, messages); };
  const auto own = [&](const std::string& path) { writeWithBagOutput(path, messages); };

  std::printf("%zu sensor_msgs/Imu messages, uncompressed, to %s; %d rounds, alternating\n",
              messages, dir.c_str(), rounds);
  std::printf("%-6s %-22s %10s %10s %10s\n", "round", "writer", "wall s", "CPU s", "system s");
  // Per writer (0: rosbag, 1: ours) the samples of wall, CPU and system time.
  std::vector<double> samples[2][3];
  const char* const names[2] = {"rosbag::Bag::write", "BagOutput (own)"};
  for (int round = 1; round <= rounds; ++round) {
    for (int turn = 0; turn < 2; ++turn) {
      const int writer = round % 2 == 1 ? turn : 1 - turn;
      const Times t = writer == 0 ? timed(rosbag_path, rosbag) : timed(own_path, own);
      samples[writer][0].push_back(t.wall_s);
      samples[writer][1].push_back(t.cpu_s);
      samples[writer][2].push_back(t.system_s);
      std::printf("%-6d %-22s %10.3f %10.3f %10.3f\n", round, names[writer], t.wall_s, t.cpu_s,
                  t.system_s);
      std::fflush(stdout);
    }
  }
  double medians[2][3];
  for (int writer = 0; writer < 2; ++writer) {
    for (int kind = 0; kind < 3; ++kind) medians[writer][kind] = median(samples[writer][kind]);
    std::printf("median %-22s %10.3f %10.3f %10.3f\n", names[writer], medians[writer][0],
                medians[writer][1], medians[writer][2]);
  }
  std::printf("rosbag / own: %.1fx wall, %.1fx CPU\n", medians[0][0] / medians[1][0],
              medians[0][1] / medians[1][1]);
  return 0;
}
