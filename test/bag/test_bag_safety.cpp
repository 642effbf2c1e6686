// The bag tools must not harm or mislead: an output that is an input under any name is refused
// (exit 2) before anything is written; a full disk stops the run with one line (exit 1) and
// leaves nothing behind; a damaged bag gives "damaged after N messages" (exit 1), never a
// signal; a run that accepts nothing exits 3 without an output; a signal removes the partial
// output; evaluate_bag skips non-finite samples, bounds and interrupts its offset search, and
// does not recommend a method that was not scored on enough of the truth.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <map>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include <geometry_msgs/WrenchStamped.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Imu.h>

#include "scene_bags.h"

using namespace bagtest;

namespace {

int lines(const std::string& text) { return int(std::count(text.begin(), text.end(), '\n')); }

bool exists(const std::string& path) {
  struct stat s;
  return ::lstat(path.c_str(), &s) == 0;
}

/// A 20 s coning IMU stream with its truth: about 1.4 MB, two chunks.
std::string writeConingBag(const TempDir& dir, const std::string& name = "in.bag",
                           Compression compression = Compression::None) {
  SceneBag scene;
  scene.motion = coning();
  scene.compression = compression;
  writeSceneBag(dir.file(name), scene);
  return dir.file(name);
}

// ---------------------------------------------------------------------------------------------
// The input is never harmed
// ---------------------------------------------------------------------------------------------

// Every spelling of the input as the output, as a bag or a CSV, and a --config file as the
// output: exit 2 with one line, the inputs unchanged byte for byte, no file written.
TEST(BagSafety, OutputThatIsAnInputIsRefused) {
  TempDir dir;
  const std::string in = writeConingBag(dir);
  const std::string before = fileText(in);
  writeText(dir.file("params.yaml"), "integrator: cf4\n");
  ASSERT_EQ(::symlink(in.c_str(), dir.file("link.bag").c_str()), 0);
  ASSERT_EQ(::link(in.c_str(), dir.file("hard.bag").c_str()), 0);
  ::mkdir(dir.file("sub").c_str(), 0755);
  const std::string cd = "cd " + quote(dir.file("")) + " && ";
  const std::vector<std::string> commands = {
      kPropagate + " " + in + " -o " + in,
      kPropagate + " " + in + " --csv " + in,
      cd + kPropagate + " in.bag -o ./in.bag",
      cd + kPropagate + " ./in.bag -o sub/../in.bag",
      kPropagate + " " + in + " -o " + dir.file("link.bag"),
      kPropagate + " " + dir.file("link.bag") + " -o " + in,
      kPropagate + " " + in + " -o " + dir.file("hard.bag"),
      kPropagate + " " + in + " --config " + dir.file("params.yaml") + " -o " +
          dir.file("params.yaml"),
      kPropagate + " " + in + " -o " + dir.file("sub"),
      kPropagate + " " + in + " -o /dev/null",
  };
  for (const std::string& command : commands) {
    const RunResult r = run(command);
    EXPECT_EQ(r.status, 2) << command << "\n" << r.output;
    EXPECT_EQ(lines(r.output), 1) << r.output;
    EXPECT_TRUE(r.output.find("is the input") != std::string::npos ||
                r.output.find("is a directory") != std::string::npos ||
                r.output.find("is not a regular file") != std::string::npos)
        << r.output;
  }
  EXPECT_EQ(fileText(in), before);
  EXPECT_EQ(fileText(dir.file("params.yaml")), "integrator: cf4\n");
  EXPECT_TRUE(noPartialFiles(dir));
  EXPECT_FALSE(exists(dir.file("in.propagated.bag")));
}

// evaluate_bag's outputs PREFIX.csv and PREFIX_series.csv against the bag (named like a CSV,
// or linked under that name) and a --config file; and the front end's chart (--png).
TEST(BagSafety, EvaluationOutputsNeverReplaceAnInput) {
  TempDir dir;
  const std::string in = writeConingBag(dir, "eval.csv");
  const std::string before = fileText(in);
  ASSERT_EQ(::symlink(in.c_str(), dir.file("x_series.csv").c_str()), 0);
  writeText(dir.file("p.csv"), "integrator: cf4\n");
  const std::string core = kEvaluateCore + " --truth /truth --offset 0 --mount 0 0 0 1 ";
  const std::string front =
      "EVALUATE_BAG_CORE=" + quote(kEvaluateCore) + " /usr/bin/python3 " + quote(kEvaluate) + " ";
  for (const std::string& command : {
           core + in + " --csv " + dir.file("eval"),
           core + in + " --csv " + dir.file("x"),
           core + in + " --config " + dir.file("p.csv") + " --csv " + dir.file("p"),
           front + in + " --truth /truth --csv " + dir.file("e") + " --png " + in,
           front + in + " --truth /truth --csv " + dir.file("e") + " --png " + dir.file("e.csv"),
       }) {
    const RunResult r = run(command);
    EXPECT_EQ(r.status, 2) << command << "\n" << r.output;
    EXPECT_NE(r.output.find("is the input"), std::string::npos) << r.output;
  }
  EXPECT_EQ(fileText(in), before);
  EXPECT_FALSE(exists(dir.file("e.csv")));
  EXPECT_TRUE(noPartialFiles(dir));
}

// An output that cannot be created: the error names the user's output, not the temporary file.
TEST(BagSafety, UnwritableOutputIsNamed) {
  TempDir dir;
  const std::string in = writeConingBag(dir);
  for (const char* option : {" -o ", " --csv "}) {
    const std::string out = dir.file("missing/out.x");
    const RunResult r = run(kPropagate + " " + in + option + out);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_EQ(r.output.find("propagate_bag: " + out + ": "), 0u) << r.output;
    EXPECT_EQ(r.output.find(".partial"), std::string::npos) << r.output;
    EXPECT_EQ(lines(r.output), 1) << r.output;
  }
}

// ---------------------------------------------------------------------------------------------
// Full disk
// ---------------------------------------------------------------------------------------------

// A write that fails mid-run (here a file-size limit of 256 KiB, which fails the write with
// EFBIG as a full disk fails it with ENOSPC, through the same path) stops the run at once:
// exit 1, one line naming the output and the reason, nothing left behind.
TEST(BagSafety, FailedWriteStopsTheRun) {
  TempDir dir;
  const std::string in = writeConingBag(dir);
  for (const char* option : {" -o ", " --csv ", " --compression lz4 -o "}) {
    const std::string out = dir.file("out.x");
    const RunResult r = run("ulimit -f 256 && " + kPropagate + " " + in + option + out);
    EXPECT_EQ(r.status, 1) << option << r.output;
    EXPECT_NE(r.output.find(out + ": write failed (File too large)"), std::string::npos)
        << r.output;
    EXPECT_EQ(lines(r.output), 1) << r.output;
    EXPECT_FALSE(exists(out));
    EXPECT_TRUE(noPartialFiles(dir));
  }
}

/// A 1 MB tmpfs for the test's lifetime, when this process may mount one (root in most
/// containers); otherwise none.
class SmallFileSystem {
 public:
  explicit SmallFileSystem(const std::string& dir) : dir_(dir) {
    ::mkdir(dir.c_str(), 0755);
    mounted_ = ::mount("tmpfs", dir.c_str(), "tmpfs", 0, "size=1m") == 0;
  }
  ~SmallFileSystem() {
    if (mounted_) ::umount(dir_.c_str());
  }
  bool mounted() const { return mounted_; }

 private:
  std::string dir_;
  bool mounted_ = false;
};

// A file system with less free space than the output needs (a 1 MB tmpfs; the 20 s coning
// output takes about 3 MB, LZ4-compressed about 0.7 MB, estimated at a quarter of the 3 MB)
// is refused before reading: exit 1, one line saying how much is needed and free; the disk is
// not filled.
TEST(BagSafety, TooLittleFreeSpaceIsRefusedAtTheStart) {
  TempDir dir;
  const std::string in = writeConingBag(dir);
  SmallFileSystem small(dir.file("small"));
  if (!small.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here";
  for (const char* option : {" -o ", " --csv "}) {
    const std::string out = dir.file("small/out.x");
    const RunResult r = run(kPropagate + " " + in + option + out);
    EXPECT_EQ(r.status, 1) << r.output;
    EXPECT_NE(r.output.find(out + ": needs about "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("MB free"), std::string::npos) << r.output;
    EXPECT_EQ(lines(r.output), 1) << r.output;
  }
  EXPECT_TRUE(dir.list().size() >= 2);
  // The estimate is not so pessimistic that a 2 s bag is refused (0.3 MB uncompressed).
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 2.0;
  writeSceneBag(dir.file("short.bag"), scene);
  const RunResult r = run(kPropagate + " " + dir.file("short.bag") + " -o " + dir.file("small/o"));
  EXPECT_EQ(r.status, 0) << r.output;
}

// Without a small file system: an output larger than the free space of the disk the test runs
// on. The dynamic model publishes publish_rate states a second of record time (docs/node.md),
// so two torques 1e7 s apart at 1000 Hz make 1e10 states, each over 100 bytes serialised: at
// least 1e12 bytes, refused at the start when the disk has less free (statvfs, as df says).
TEST(BagSafety, OutputLargerThanTheDiskIsRefusedAtTheStart) {
  TempDir dir;
  const double span = 1e7, rate = 1000.0, least_per_state = 100.0;
  struct statvfs fs {};
  ASSERT_EQ(::statvfs(dir.file("").c_str(), &fs), 0);
  const double free_bytes = double(fs.f_bavail) * double(fs.f_frsize);
  if (free_bytes >= rate * span * least_per_state) GTEST_SKIP() << "a disk of over 1 TB free";
  {
    rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
    for (const double t : {0.0, span}) {
      geometry_msgs::WrenchStamped m;
      m.header.stamp = rosTime(stampAt(t));
      m.header.frame_id = "base_link";
      m.wrench.torque.z = 0.3;
      bag.write("/torque", m.header.stamp, m);
    }
  }
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set inertia=[2,3,4] --set torque_input=true --set rate_input=none" +
                          " --set publish_rate=1000 --no-progress");
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("needs about "), std::string::npos) << r.output;
  EXPECT_EQ(lines(r.output), 1) << r.output;
  EXPECT_FALSE(exists(dir.file("out.bag")));
}

// ---------------------------------------------------------------------------------------------
// Damaged bags
// ---------------------------------------------------------------------------------------------

/// Overwrites `n` bytes at `position` with a pattern.
// Three Imu messages 10 ms apart on /imu/data_raw, each with FRAME_ID.
void writeImuBag(const std::string& path, const std::string& frame_id) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (int k = 0; k < 3; ++k) {
    sensor_msgs::Imu m;
    m.header.stamp = rosTime(stampAt(0.01 * k));
    m.header.frame_id = frame_id;
    bag.write("/imu/data_raw", m.header.stamp, m);
  }
}

void damage(const std::string& path, std::uint64_t position, std::size_t n) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(position));
  for (std::size_t i = 0; i < n; ++i) f.put(static_cast<char>(0xA5 ^ (i * 37)));
}

struct Damaged {
  Compression compression;
  const char* name;
};
const Damaged kCompressions[] = {
    {Compression::None, "none"}, {Compression::Bz2, "bz2"}, {Compression::Lz4, "lz4"}};

// 64 bytes overwritten in the middle of the second chunk's data, for each compression: both
// tools say "damaged after N messages" naming the file, with N the messages of the chunk before
// it (rosbag's index says how many); exit 1, one line, nothing left behind.
TEST(BagSafety, DamagedChunkIsNamed) {
  for (const Damaged& d : kCompressions) {
    TempDir dir;
    const std::string in = writeConingBag(dir, "in.bag", d.compression);
    const auto chunks = chunkData(in);
    ASSERT_GE(chunks.size(), 2u) << d.name;
    damage(in, chunks[1].position + chunks[1].size / 2, 64);
    for (const std::string& command :
         {kPropagate + " " + in + " -o " + dir.file("out.bag"),
          kPropagate + " " + in + " --csv " + dir.file("out.csv"),
          kEvaluateCore + " " + in + " --truth /truth --csv " + dir.file("eval")}) {
      const RunResult r = run(command);
      EXPECT_EQ(r.status, 1) << d.name << ": " << command << "\n" << r.output;
      EXPECT_NE(r.output.find(in + ": damaged after "), std::string::npos) << r.output;
      EXPECT_NE(r.output.find("(chunk 2 of "), std::string::npos) << r.output;
      EXPECT_EQ(lines(r.output), 1) << r.output;
      // The first chunk's messages: some, not all 8002 of the bag.
      std::smatch m;
      ASSERT_TRUE(std::regex_search(r.output, m, std::regex("damaged after (\\d+) messages")));
      EXPECT_GT(std::stoi(m[1]), 0);
      EXPECT_LT(std::stoi(m[1]), 8002);
    }
    EXPECT_EQ(dir.list(), std::vector<std::string>{"in.bag"});
  }
}

// A bag of format version 1.2 (ROS before 2010) is refused naming its version and the one
// accepted, in one line, not as a damaged bag.
TEST(BagSafety, OtherFormatVersionIsNamed) {
  TempDir dir;
  const std::string in = dir.file("old.bag");
  writeText(in, std::string("#ROSBAG V1.2\n") + std::string(4096, '\0'));
  const RunResult r = run(kPropagate + " " + in + " -o " + dir.file("out.bag"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find(in + ": a bag of format version 1.2; accepted: version 2.0"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(lines(r.output), 1) << r.output;
}

// A frame id of 10 MB from the bag is logged as the node logs it (logText): its first 64 bytes
// and its length, so the line stays short.
TEST(BagSafety, HugeFrameIdIsCappedInTheLog) {
  TempDir dir;
  const std::string in = dir.file("in.bag");
  writeImuBag(in, std::string(10 * 1000 * 1000, 'f'));
  const RunResult r = run(kPropagate + " " + in + " -o " + dir.file("out.bag") + " --no-progress");
  EXPECT_NE(r.output.find("...(10000000 bytes)"), std::string::npos) << r.output.size();
  EXPECT_LT(r.output.size(), 4000u);
}

// A frame id with tf1's leading '/' is warned about once; 10 MB of it is capped by the one text
// rule (quoted_text.h), as the node's line is.
TEST(BagSafety, HugeLeadingSlashFrameIdIsCappedInTheWarning) {
  TempDir dir;
  const std::string in = dir.file("in.bag");
  writeImuBag(in, "/" + std::string(10 * 1000 * 1000, 'f'));
  const RunResult r = run(kPropagate + " " + in + " -o " + dir.file("out.bag") + " --no-progress");
  EXPECT_NE(r.output.find("bytes)"), std::string::npos) << r.output.substr(0, 2000);
  EXPECT_LT(r.output.size(), 4000u);
}

// A frame parameter of 100 kB would be carried by every output message (2.2 GB for 11 000
// states): refused before anything is read, exit 2, in one short line.
TEST(BagSafety, HugeFrameParameterIsRefused) {
  TempDir dir;
  const std::string in = writeConingBag(dir);
  const RunResult r = run(kPropagate + " " + in + " -o " + dir.file("out.bag") +
                          " --no-progress --set fixed_frame=" + std::string(100000, 'w'));
  EXPECT_EQ(r.status, 2) << r.output.substr(0, 500);
  EXPECT_NE(r.output.find("at most 256 bytes"), std::string::npos) << r.output.substr(0, 500);
  EXPECT_LT(r.output.size(), 2000u);
  EXPECT_FALSE(exists(dir.file("out.bag")));
}

// An output that is a symlink is written where it points, the link kept: a dangling one (its
// target created), and one to an existing file (replaced).
TEST(BagSafety, SymlinkOutputIsWrittenWhereItPoints) {
  TempDir dir;
  const std::string in = writeConingBag(dir);
  ASSERT_EQ(::symlink("target.bag", dir.file("dangling.bag").c_str()), 0);
  RunResult r = run(kPropagate + " " + in + " -o " + dir.file("dangling.bag") + " --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  struct stat s {};
  ASSERT_EQ(::lstat(dir.file("dangling.bag").c_str(), &s), 0);
  EXPECT_TRUE(S_ISLNK(s.st_mode));
  ASSERT_EQ(::lstat(dir.file("target.bag").c_str(), &s), 0);
  EXPECT_TRUE(S_ISREG(s.st_mode));
  EXPECT_GT(s.st_size, 1000);
  // Again, now that the target exists.
  r = run(kPropagate + " " + in + " -o " + dir.file("dangling.bag") + " --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  ASSERT_EQ(::lstat(dir.file("dangling.bag").c_str(), &s), 0);
  EXPECT_TRUE(S_ISLNK(s.st_mode));
  EXPECT_TRUE(noPartialFiles(dir));
}

// SIGKILL leaves the partial output (no handler runs): the next run of the same output removes
// those of runs no longer running, and says so; one of a run still going (this test) stays.
TEST(BagSafety, PartialOutputsOfKilledRunsAreRemovedByTheNext) {
  TempDir dir;
  const std::string in = writeConingBag(dir);
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  ASSERT_GT(gone, 0);
  ::waitpid(gone, nullptr, 0);  // a pid no longer running
  const std::string dead = dir.file(".out.bag.partial-" + std::to_string(gone));
  const std::string alive = dir.file(".out.bag.partial-" + std::to_string(::getpid()));
  writeText(dead, "left by a killed run");
  writeText(alive, "a run still going");
  const RunResult r = run(kPropagate + " " + in + " -o " + dir.file("out.bag") + " --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_FALSE(exists(dead));
  EXPECT_TRUE(exists(alive));
  EXPECT_NE(r.output.find("removed 1 partial output(s)"), std::string::npos) << r.output;
}

// Damage anywhere: 16 bytes overwritten at 33 places spread over the file (headers, chunk data,
// index records, the index section), for each compression. Whatever is hit, propagate_bag
// ends with an exit code it documents (0: the damage only changed values in a message or a
// time in the index; 1: damaged; 3: nothing accepted), never a signal (without the structure
// check rosbag's reader died of SIGSEGV at 15 of 60 such places in a bz2 bag, 4 of 60 in an
// lz4 one), and leaves an output only with exit 0. In a compressed bag every hit of a chunk's
// data is found (bz2's CRC, roslz4's checksum). evaluate_bag reads bags through the same
// code (DamagedChunkIsNamed).
TEST(BagSafety, DamageAnywhereNeverCrashes) {
  for (const Damaged& d : kCompressions) {
    TempDir dir;
    SceneBag scene;
    scene.motion = coning();
    scene.duration = 8.0;
    scene.compression = d.compression;
    writeSceneBag(dir.file("good.bag"), scene);
    const std::string good = fileText(dir.file("good.bag"));
    const auto chunks = chunkData(dir.file("good.bag"));
    std::map<int, int> statuses;
    for (int k = 1; k <= 33; ++k) {
      const std::string in = dir.file("in.bag");
      const std::uint64_t at = good.size() * k / 34;
      writeText(in, good);
      damage(in, at, 16);
      const RunResult p = run(kPropagate + " " + in + " -o " + dir.file("out.bag"));
      ++statuses[p.status];
      EXPECT_TRUE(p.status == 0 || p.status == 1 || p.status == 3)
          << d.name << " at " << at << ": " << p.status << "\n"
          << p.output;
      const bool in_chunk = std::any_of(chunks.begin(), chunks.end(), [at](const ChunkData& c) {
        return at + 16 > c.position && at < c.position + c.size;
      });
      if (d.compression != Compression::None && in_chunk) {
        EXPECT_EQ(p.status, 1) << d.name << " at " << at << "\n" << p.output;
      }
      EXPECT_EQ(exists(dir.file("out.bag")), p.status == 0) << p.output;
      std::remove(dir.file("out.bag").c_str());
      ASSERT_TRUE(noPartialFiles(dir));
    }
    std::string summary;
    for (const auto& [status, n] : statuses) {
      summary += " exit " + std::to_string(status) + ": " + std::to_string(n);
    }
    std::cout << "  " << d.name << ", propagate_bag:" << summary << "\n";
  }
}

// A tf truth message whose transform count is damaged (2^24 in a message of about 200 bytes)
// in an uncompressed bag, where no checksum can tell: deserialising would make room for 2^24
// transforms (gigabytes) before finding the message short; the count is checked against the
// message's size first, and the bag is reported damaged after the messages before it.
TEST(EvaluateBagSafety, DamagedTransformCountIsRefused) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 2.0;
  scene.truth = TruthType::Tf;
  scene.truth_topic = "/tf";
  writeSceneBag(dir.file("in.bag"), scene);
  std::string bytes = fileText(dir.file("in.bag"));
  // A TFMessage: count, then the first transform's header (seq, stamp, frame_id "map").
  const std::string frame = std::string("\x03\x00\x00\x00", 4) + "map";
  const auto at = bytes.find(frame, bytes.size() / 2);
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(bytes.compare(at - 16, 4, std::string("\x02\x00\x00\x00", 4)), 0);
  bytes.replace(at - 16, 4, std::string("\x00\x00\x00\x01", 4));  // 2^24
  writeText(dir.file("in.bag"), bytes);
  const RunResult r = run("ulimit -v 2000000 && " + kEvaluateCore + " " + dir.file("in.bag") +
                          " --truth-tf map body_truth --csv " + dir.file("eval"));
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find(dir.file("in.bag") + ": damaged after "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("16777216 transforms cannot fit in "), std::string::npos) << r.output;
  EXPECT_EQ(dir.list(), std::vector<std::string>{"in.bag"});
}

// ---------------------------------------------------------------------------------------------
// Exit codes
// ---------------------------------------------------------------------------------------------

// The run completes but accepts nothing (every IMU message is in a frame the bag has no static
// transform for): exit 3, the summary says "0 accepted" and why ("no-tf" and the count), no
// output.
TEST(BagSafety, NothingAcceptedExitsThree) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 2.0;
  scene.rate_frame = "imu_link";
  const Written w = writeSceneBag(dir.file("in.bag"), scene);
  const std::string n = std::to_string(w.rate_stamps.size());
  for (const char* option : {" -o ", " --csv "}) {
    const RunResult r = run(kPropagate + " " + dir.file("in.bag") + option + dir.file("out"));
    EXPECT_EQ(r.status, 3) << r.output;
    EXPECT_NE(r.output.find(n + " messages (/imu/data_raw " + n +
                            "), 0 accepted, dropped: dropped_no_tf " + n),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("nothing written"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("no input accepted (no transform"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("; no output written"), std::string::npos) << r.output;
    EXPECT_EQ(dir.list(), std::vector<std::string>{"in.bag"});
  }
}

// Rates in a frame with no path to body_frame (an IMU alone, no /tf): the run and --dry-run
// (before reading the rates) name both frames and the setting that takes the IMU's frame as
// the body (docs/bag_tools.md); with that setting the same bag runs.
TEST(BagSafety, NoPathToTheBodyNamesBothFramesAndTheSetting) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 1.0;
  scene.rate_frame = "imu_link";
  writeSceneBag(dir.file("in.bag"), scene);
  const std::string in = kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag");
  for (const std::string& options : {std::string(), std::string(" --dry-run")}) {
    const RunResult r = run(in + options);
    EXPECT_EQ(r.status, 3) << options << r.output;
    for (const char* text : {"'imu_link'", "body_frame 'base_link'", "--set body_frame=imu_link"}) {
      EXPECT_NE(r.output.find(text), std::string::npos) << options << ": " << text << r.output;
    }
  }
  EXPECT_EQ(run(in + " --set body_frame=imu_link").status, 0);
}

// tf1's leading '/' in the rates' frame and in body_frame: read without it, one warning per
// frame, and never tf2's error per message ("cannot start with a '/'").
TEST(BagSafety, LeadingSlashFramesAreReadWithoutIt) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 1.0;
  scene.rate_frame = "/imu";
  const Written w = writeSceneBag(dir.file("in.bag"), scene);
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") +
                          " --set body_frame=/imu --set fixed_frame=/odom");
  EXPECT_EQ(r.status, 0) << r.output;
  const std::string n = std::to_string(w.rate_stamps.size());
  EXPECT_NE(r.output.find(n + " accepted"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("cannot start with"), std::string::npos) << r.output;
  for (const char* name : {"body_frame: frame id '/imu'", "fixed_frame: frame id '/odom'",
                           "warning: frame id '/imu' has a leading '/'"}) {
    EXPECT_NE(r.output.find(name), std::string::npos) << name << r.output;
  }
  const RunResult spaced = run(kPropagate + " " + dir.file("in.bag") + " -o " +
                               dir.file("out2.bag") + " --set \"body_frame=base link\"");
  EXPECT_EQ(spaced.status, 2) << spaced.output;
  EXPECT_NE(spaced.output.find("spaces"), std::string::npos) << spaced.output;
}

// --help lists every exit code; a missing input is exit 1; bad options exit 2.
TEST(BagSafety, ExitCodesAreDocumentedAndUsed) {
  for (const std::string& program : {kPropagate, kEvaluateCore}) {
    const RunResult help = run(program + " --help");
    EXPECT_EQ(help.status, 0);
    for (const char* code : {"  0 ", "  1 ", "  2 ", "  3 ", "  128+N "}) {
      EXPECT_NE(help.output.find(code), std::string::npos) << program << " " << code;
    }
  }
  TempDir dir;
  EXPECT_EQ(run(kPropagate + " " + dir.file("missing.bag")).status, 1);
  EXPECT_EQ(run(kEvaluateCore + " " + dir.file("missing.bag") + " --truth /t").status, 1);
  EXPECT_EQ(run(kPropagate).status, 2);
  EXPECT_EQ(run(kEvaluateCore).status, 2);
  EXPECT_EQ(run(kEvaluateCore + " " + dir.file("missing.bag")).status, 2);  // no truth
  EXPECT_EQ(run(kPropagate + " in.bag -o").status, 2);
  EXPECT_EQ(run(kPropagate + " in.bag -o ''").status, 2);
  EXPECT_EQ(run(kPropagate + " in.bag --config /").status, 2);
  const RunResult directory = run(kPropagate + " " + dir.file(""));
  EXPECT_EQ(directory.status, 1);
  EXPECT_NE(directory.output.find("is a directory, not a bag"), std::string::npos);
}

/// Runs `command` in the background, sends `signals` (one or two) as soon as a partial output
/// appears in `dir`, and returns the exit status; -2 when the run ended before that.
int interruptWhenWriting(const TempDir& dir, const std::string& command,
                         const std::vector<int>& signals) {
  const std::string pid_file = dir.file("pid");
  const std::string status_file = dir.file("status");
  std::system(("(" + command + " & echo $! > " + quote(pid_file) + "; wait $!; echo $? > " +
               quote(status_file) + ") >/dev/null 2>&1 &")
                  .c_str());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  bool sent = false;
  while (std::chrono::steady_clock::now() < deadline) {
    if (!sent && !noPartialFiles(dir)) {
      const int pid = std::stoi(fileText(pid_file));
      for (int s : signals) ::kill(pid, s);
      sent = true;
    }
    const std::string status = fileText(status_file);
    if (!status.empty() && status.back() == '\n') {
      std::remove(status_file.c_str());
      std::remove(pid_file.c_str());
      return sent ? std::stoi(status) : -2;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return -3;
}

// SIGHUP, SIGINT and SIGTERM while the output is being written: exit 128 + the signal and the
// partial output removed; a second signal right after the first too (the handler removes it and
// exits with 128 + the signal it handled second: when both are pending at once, Linux delivers
// the lower-numbered first, so after SIGTERM then SIGINT either may be the second).
TEST(BagSafety, SignalsRemoveThePartialOutput) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 300.0;  // 60001 inputs: the output takes a few tenths of a second
  scene.truth = TruthType::None;
  writeSceneBag(dir.file("in.bag"), scene);
  const std::string command =
      kPropagate + " " + dir.file("in.bag") + " -o " + dir.file("out.bag") + " --no-progress";
  int tried = 0;
  for (const std::vector<int>& signals : std::vector<std::vector<int>>{
           {SIGHUP}, {SIGINT}, {SIGTERM}, {SIGHUP, SIGHUP}, {SIGTERM, SIGINT}}) {
    const int status = interruptWhenWriting(dir, command, signals);
    if (status == -2) continue;  // finished before the partial file was seen: nothing to test
    ++tried;
    if (signals.size() == 1 || signals.front() == signals.back()) {
      EXPECT_EQ(status, 128 + signals.back()) << signals.size() << " signals";
    } else {
      EXPECT_TRUE(status == 128 + signals.front() || status == 128 + signals.back())
          << "exit " << status << " after signals " << signals.front() << ", " << signals.back();
    }
    EXPECT_TRUE(noPartialFiles(dir));
    EXPECT_FALSE(exists(dir.file("out.bag")));
  }
  EXPECT_GE(tried, 3);
}

// ---------------------------------------------------------------------------------------------
// evaluate_bag
// ---------------------------------------------------------------------------------------------

struct Evaluated {
  RunResult run;
  std::map<std::string, std::vector<std::pair<std::string, std::string>>> methods;
  std::string recommended;
};

Evaluated evaluateBag(const TempDir& dir, const std::string& bag, const std::string& arguments) {
  Evaluated e;
  std::remove(dir.file("eval.csv").c_str());
  e.run = run(kEvaluateCore + " " + bag + " --csv " + dir.file("eval") + " " + arguments);
  if (e.run.status != 0) return e;
  for (const auto& row : readCsv(dir.file("eval.csv"))) {
    e.methods[field(row, "method")] = row;
    if (field(row, "recommended") == "1") e.recommended = field(row, "method");
  }
  return e;
}

// One NaN among 18001 gyro samples (90 s at 200 Hz, the offset and mount estimated): skipped
// and counted; every number stays finite, and the offset and the recommendation are those of
// the same bag without it.
TEST(EvaluateBagSafety, NonFiniteSampleIsSkipped) {
  TempDir dir;
  SceneBag scene;
  scene.motion = tumbling();
  scene.duration = 90.0;
  scene.truth_offset = 0.01;
  writeSceneBag(dir.file("clean.bag"), scene);
  scene.non_finite = {9000};
  writeSceneBag(dir.file("spoilt.bag"), scene);
  const Evaluated clean = evaluateBag(dir, dir.file("clean.bag"), "--truth /truth");
  const Evaluated nan = evaluateBag(dir, dir.file("spoilt.bag"), "--truth /truth");
  ASSERT_EQ(clean.run.status, 0) << clean.run.output;
  ASSERT_EQ(nan.run.status, 0) << nan.run.output;
  EXPECT_NE(nan.run.output.find("skipped: 1 rate samples with a non-finite component"),
            std::string::npos)
      << nan.run.output;
  EXPECT_EQ(nan.run.output.find(" nan"), std::string::npos) << nan.run.output;
  EXPECT_EQ(nan.run.output.find("-nan"), std::string::npos) << nan.run.output;
  EXPECT_EQ(nan.recommended, clean.recommended) << nan.run.output << clean.run.output;
  for (const auto& [name, row] : nan.methods) {
    for (const char* column : {"offset_s", "max_error_rad", "rms_error_rad", "drift_rad_per_s",
                               "rpe_1s_rms_rad", "rpe_10s_rms_rad"}) {
      EXPECT_TRUE(std::isfinite(std::stod(field(row, column)))) << name << " " << column;
    }
    EXPECT_NEAR(std::stod(field(row, "offset_s")),
                std::stod(field(clean.methods.at(name), "offset_s")), 1e-4);
  }
}

// Times on the command line: non-finite and beyond the range of ROS time (2^32 s) are usage
// errors (exit 2, one line, no CSV).
TEST(EvaluateBagSafety, AbsurdTimesAreUsageErrors) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 2.0;
  writeSceneBag(dir.file("in.bag"), scene);
  for (const char* arguments :
       {"--max-offset 1e300", "--max-offset 1e308", "--max-offset nan", "--max-offset inf",
        "--max-offset -1", "--offset 1e300", "--offset -1e308", "--offset 4294967297",
        "--calibration 1e308", "--calibration 0", "--truth-gap 1e300", "--mount 0 0 0 0",
        "--mount 1 0 0 nan", "--integrators rk5", "--rate-samples sometimes", "--set max_dt=-1",
        "--offset", "--no-such-option"}) {
    const Evaluated e =
        evaluateBag(dir, dir.file("in.bag"), std::string("--truth /truth ") + arguments);
    EXPECT_EQ(e.run.status, 2) << arguments << "\n" << e.run.output;
    EXPECT_EQ(lines(e.run.output), 1) << e.run.output;
  }
  const Evaluated e = evaluateBag(dir, dir.file("in.bag"), "");
  EXPECT_EQ(e.run.status, 2) << e.run.output;
  EXPECT_NE(e.run.output.find("--truth TOPIC or --truth-tf"), std::string::npos);
  EXPECT_EQ(dir.list(), std::vector<std::string>{"in.bag"});
}

// The largest accepted --max-offset (2^32 s) on 60 s of a body torqued from rest (|w| grows
// with time: one offset matches, unlike a periodic motion) with the truth 25 ms late: the
// search is cut to the offsets at which half of the rates can meet the truth (+-30 s about
// the 25 ms) and its grid widened to bound it; it ends in bounded time, says what it
// searched, and still finds the offset (the refinement within one widened step).
TEST(EvaluateBagSafety, HugeMaxOffsetIsBounded) {
  TempDir dir;
  SceneBag scene;
  scene.motion = torquedFromRest(Eigen::Vector3d(1, 2, 2) / 3.0, 0.3, 4.0);
  scene.duration = 60.0;
  scene.truth_offset = 0.025;
  writeSceneBag(dir.file("in.bag"), scene);
  const auto start = std::chrono::steady_clock::now();
  const Evaluated e = evaluateBag(dir, dir.file("in.bag"),
                                  "--truth /truth --max-offset 4294967296 --integrators cf4 "
                                  "--rate-samples instantaneous");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_EQ(e.run.status, 0) << e.run.output;
  EXPECT_LT(seconds, 30.0);
  std::smatch range;
  ASSERT_TRUE(std::regex_search(e.run.output, range, std::regex("searched (\\S+)\\.\\.(\\S+) s")))
      << e.run.output;
  EXPECT_NEAR(std::stod(range[1]), -30.0 + 0.025, 0.01) << e.run.output;
  EXPECT_NEAR(std::stod(range[2]), 30.0 + 0.025, 0.01) << e.run.output;
  EXPECT_NE(e.run.output.find("widened to bound the search"), std::string::npos) << e.run.output;
  EXPECT_NEAR(std::stod(field(e.methods.at("cf4/instantaneous"), "offset_s")), 0.025, 1e-3)
      << e.run.output;
}

// SIGINT or SIGTERM at any moment of a run whose offset search takes about a second (+-30 s on
// 60 s of coning, whose vectors are matched through the best mount at each offset): the run
// ends with 128 + the signal, within a second of it (one trial offset takes well under a
// millisecond; the rest is slack for a loaded machine), or had ended before it; no CSV unless
// it ended with 0; at least four of the eight signals are seen and said ("interrupted").
TEST(EvaluateBagSafety, OffsetSearchIsInterruptible) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 60.0;
  writeSceneBag(dir.file("in.bag"), scene);
  const std::string command = kEvaluateCore + " " + dir.file("in.bag") +
                              " --truth /truth --max-offset 30 --integrators cf4 "
                              "--rate-samples instantaneous --no-progress --csv " +
                              dir.file("eval");
  int interrupted = 0;
  for (int k = 1; k <= 8; ++k) {
    const double delay = 0.15 * k;
    const char* signal = k % 2 ? "INT" : "TERM";
    std::remove(dir.file("eval.csv").c_str());
    const auto start = std::chrono::steady_clock::now();
    char prefix[64];
    std::snprintf(prefix, sizeof prefix, "timeout --preserve-status -s %s %.2f ", signal, delay);
    const RunResult r = run(prefix + command);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (r.status == 0) {
      EXPECT_LT(seconds, delay + 1.0);
      continue;
    }
    EXPECT_EQ(r.status, 128 + (k % 2 ? SIGINT : SIGTERM)) << r.output;
    EXPECT_LT(seconds, delay + 1.0) << "signal after " << delay << " s";
    EXPECT_FALSE(exists(dir.file("eval.csv")));
    EXPECT_TRUE(noPartialFiles(dir));
    // A signal in the first tenth of a second or so (more on a loaded machine) comes before the
    // program has set its handlers: the default action ends it, with the same status and
    // nothing written. After that it says so.
    if (r.output.find("interrupted") != std::string::npos) ++interrupted;
  }
  EXPECT_GE(interrupted, 4);
}

// max_dt below the sample period (1e-6 s, the least accepted) makes every sample a gap: the state
// is held, nothing is integrated, and by the rule in --help (at least half of the compared samples,
// and at least 100, integrated from the one before) no method is scored: exit 3, "no
// recommendation" and why, the table still printed, no CSV. An offset beyond the data (nothing
// compared) too.
TEST(EvaluateBagSafety, NoRecommendationWithoutEnoughTruth) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 10.0;
  writeSceneBag(dir.file("in.bag"), scene);
  for (const char* arguments :
       {"--set max_dt=1e-6", "--set max_dt=0.004", "--offset 1000 --mount 0 0 0 1"}) {
    const Evaluated e =
        evaluateBag(dir, dir.file("in.bag"), std::string("--truth /truth ") + arguments);
    EXPECT_EQ(e.run.status, 3) << arguments << "\n" << e.run.output;
    EXPECT_NE(e.run.output.find("no recommendation: no method was scored"), std::string::npos)
        << e.run.output;
    EXPECT_NE(e.run.output.find("cf4/instantaneous"), std::string::npos) << e.run.output;
    EXPECT_EQ(e.run.output.find("<- recommended"), std::string::npos) << e.run.output;
    EXPECT_FALSE(exists(dir.file("eval.csv")));
  }
  // The same bag with max_dt above the period: every method scored, one recommended.
  const Evaluated e = evaluateBag(dir, dir.file("in.bag"), "--truth /truth --set max_dt=0.006");
  EXPECT_EQ(e.run.status, 0) << e.run.output;
  EXPECT_EQ(e.run.output.find("(not scored)"), std::string::npos) << e.run.output;
  EXPECT_FALSE(e.recommended.empty());
}

// The front end passes the core's exit code on (2, 3), and its own usage errors are 2.
TEST(EvaluateBagSafety, FrontEndPassesExitCodesOn) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 3.0;
  writeSceneBag(dir.file("in.bag"), scene);
  const std::string front = "EVALUATE_BAG_CORE=" + quote(kEvaluateCore) + " /usr/bin/python3 " +
                            quote(kEvaluate) + " " + dir.file("in.bag") + " --csv " +
                            dir.file("e") + " ";
  EXPECT_EQ(run(front + "--truth /truth --max-offset 1e300").status, 2);
  EXPECT_EQ(run(front + "--truth /truth --set max_dt=1e-6").status, 3);
  EXPECT_EQ(run(front + "--truth /truth --png").status, 2);
  EXPECT_EQ(run(front + "--truth /nothing").status, 1);
  EXPECT_FALSE(exists(dir.file("e.png")));
}

}  // namespace
