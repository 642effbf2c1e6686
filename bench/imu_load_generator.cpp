#include "imu_load_generator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include <sys/prctl.h>

namespace attitude_propagator_bench {

namespace {

using SteadyClock = std::chrono::steady_clock;

// Sleeps until `deadline` when at least kMinSleep ahead of it; closer than that it returns at
// once (the message goes out a little early, the schedule keeps the average rate). No busy
// wait: on a 2-core machine a spinning sender would take the core the receiving thread needs
// and inflate the measured latency. The timer slack is set to 1 ns in run(), so a sleep ends
// within microseconds of its deadline instead of the default 50 us.
void waitUntil(SteadyClock::time_point deadline) {
  constexpr auto kMinSleep = std::chrono::microseconds(20);
  const auto ahead = deadline - SteadyClock::now();
  if (ahead >= kMinSleep) std::this_thread::sleep_for(ahead);
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  const std::size_t i = std::min(v.size() - 1, static_cast<std::size_t>(p * v.size()));
  std::nth_element(v.begin(), v.begin() + i, v.end());
  return v[i];
}

// A slow coning-like body rate (rad/s), so the propagator integrates something non-trivial.
void fillRate(sensor_msgs::Imu& msg, double t) {
  msg.angular_velocity.x = -0.03;
  msg.angular_velocity.y = -0.7 * std::sin(6.9 * t);
  msg.angular_velocity.z = 0.7 * std::cos(6.9 * t);
}

}  // namespace

ImuLoadGenerator::ImuLoadGenerator(ros::NodeHandle nh, ros::NodeHandle pnh) : nh_(nh) {
  std::vector<double> rates{1000, 2000, 5000, 10000, 20000, 50000, 100000, 200000};
  pnh.getParam("rates", rates);
  pnh.param("seconds", seconds_, seconds_);
  pnh.param("settle", settle_, settle_);
  pnh.param<std::string>("mode", mode_, "node");
  pnh.param<std::string>("out", out_, "node_bench.csv");
  phases_.resize(rates.size());
  for (std::size_t i = 0; i < rates.size(); ++i) phases_[i].rate_hz = rates[i];
  pub_ = nh_.advertise<sensor_msgs::Imu>("imu/data_raw", 100000);
  sub_ = nh_.subscribe("imu/data", 100000, &ImuLoadGenerator::onOutput, this,
                       ros::TransportHints().tcpNoDelay());
  thread_ = std::thread([this] { run(); });
}

ImuLoadGenerator::~ImuLoadGenerator() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void ImuLoadGenerator::run() {
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);  // this thread's sleeps end on time
  // Wait for the propagator to connect both ways, then let the connections settle.
  while (!stop_ && (pub_.getNumSubscribers() == 0 || sub_.getNumPublishers() == 0)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::seconds(1));
  for (Phase& phase : phases_) {
    if (stop_) return;
    sendPhase(phase);
    waitForQuiet();
    std::lock_guard<std::mutex> lock(mutex_);
    ROS_INFO("load generator (%s): %.0f Hz: sent %ld, received %zu", mode_.c_str(), phase.rate_hz,
             phase.sent, phase.latencies_ms.size());
  }
  writeCsv();
  done_ = true;
}

// One message per period on a fixed schedule (message i at start + i / rate); a sender that
// falls behind sends at once until it is back on schedule, and the achieved send rate is
// reported next to the offered one.
void ImuLoadGenerator::sendPhase(Phase& phase) {
  const auto period = std::chrono::duration<double>(1.0 / phase.rate_hz);
  const long count = std::lround(phase.rate_hz * seconds_);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    phase.begin = ros::Time::now();
  }
  const auto start = SteadyClock::now();
  for (long i = 0; i < count && !stop_; ++i) {
    waitUntil(start + std::chrono::duration_cast<SteadyClock::duration>(i * period));
    sensor_msgs::ImuPtr msg(new sensor_msgs::Imu);  // shared_ptr publish: zero copy in-process
    msg->header.frame_id = "base_link";
    msg->header.stamp = ros::Time::now();
    fillRate(*msg, msg->header.stamp.toSec());
    pub_.publish(msg);
    ++phase.sent;
  }
  phase.end = ros::Time::now();
}

// In-flight messages of a phase are still counted after its last send: wait until nothing has
// arrived for `settle` seconds (at most ten times that).
void ImuLoadGenerator::waitForQuiet() {
  const auto give_up = SteadyClock::now() + std::chrono::duration<double>(10 * settle_);
  while (!stop_ && SteadyClock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const long quiet_ns = SteadyClock::now().time_since_epoch().count() - last_receipt_ns_;
    if (quiet_ns > settle_ * 1e9) return;
  }
}

void ImuLoadGenerator::onOutput(const sensor_msgs::Imu::ConstPtr& msg) {
  const ros::Time now = ros::Time::now();
  last_receipt_ns_ = SteadyClock::now().time_since_epoch().count();
  const ros::Time& stamp = msg->header.stamp;
  std::lock_guard<std::mutex> lock(mutex_);
  // Phases run one after the other: the message belongs to the last one begun before its stamp.
  for (auto phase = phases_.rbegin(); phase != phases_.rend(); ++phase) {
    if (!phase->begin.isZero() && stamp >= phase->begin) {
      phase->latencies_ms.push_back((now - stamp).toSec() * 1e3);
      return;
    }
  }
}

void ImuLoadGenerator::writeCsv() const {
  const std::string tmp = out_ + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (f == nullptr) {
    ROS_ERROR("load generator: cannot write %s", tmp.c_str());
    return;
  }
  std::fprintf(f,
               "mode,rate_hz,seconds,sent,sent_rate_hz,received,delivered_fraction,"
               "latency_p50_ms,latency_p99_ms,latency_max_ms\n");
  std::lock_guard<std::mutex> lock(mutex_);
  for (const Phase& p : phases_) {
    const double elapsed = (p.end - p.begin).toSec();
    const std::size_t received = p.latencies_ms.size();
    std::fprintf(f, "%s,%.0f,%.3f,%ld,%.1f,%zu,%.6f,%.4f,%.4f,%.4f\n", mode_.c_str(), p.rate_hz,
                 elapsed, p.sent, p.sent / elapsed, received,
                 p.sent ? static_cast<double>(received) / p.sent : 0.0,
                 percentile(p.latencies_ms, 0.5), percentile(p.latencies_ms, 0.99),
                 percentile(p.latencies_ms, 1.0));
  }
  std::fclose(f);
  std::rename(tmp.c_str(), out_.c_str());
}

}  // namespace attitude_propagator_bench
