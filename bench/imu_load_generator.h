// Load generator of the node benchmark (docs/design.md §8): publishes sensor_msgs/Imu on
// imu/data_raw at rising rates, a few seconds each, and listens on imu/data. Every input header is
// stamped with its send time; the node copies the input header into imu/data, so on receipt now -
// stamp is the input-to-output latency, and the stamp tells which rate it belongs to. Writes one
// CSV row per rate when done.
//
// Private parameters: rates (list of Hz), seconds (per rate), settle (s, quiet time after each
// rate), mode (label in the CSV: node or nodelet), out (CSV path, written atomically).
#pragma once

#include <atomic>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <ros/ros.h>
#include <sensor_msgs/Imu.h>

namespace attitude_propagator_bench {

class ImuLoadGenerator {
 public:
  /// Starts the sending thread at once; subscriptions run on nh's callback queue.
  ImuLoadGenerator(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~ImuLoadGenerator();

  bool done() const { return done_; }

 private:
  /// The send times [begin, end] of one rate, and what came back from it.
  struct Phase {
    double rate_hz = 0.0;
    ros::Time begin, end;
    long sent = 0;
    std::vector<double> latencies_ms;  // guarded by mutex_
  };

  void run();
  void sendPhase(Phase& phase);
  void waitForQuiet();
  void onOutput(const sensor_msgs::Imu::ConstPtr& msg);
  void writeCsv() const;

  ros::NodeHandle nh_;
  ros::Publisher pub_;
  ros::Subscriber sub_;
  std::vector<Phase> phases_;
  double seconds_ = 3.0;
  double settle_ = 0.5;
  std::string mode_;
  std::string out_;
  mutable std::mutex mutex_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> done_{false};
  std::atomic<long> last_receipt_ns_{0};
  std::thread thread_;
};

}  // namespace attitude_propagator_bench
