#include "bag_input.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <fstream>
#include <set>

#include "bag_check.h"

namespace attitude_propagator {
namespace tools {

void openBag(rosbag::Bag& bag, const std::string& path) {
  struct stat file {};
  if (::stat(path.c_str(), &file) == 0 && S_ISDIR(file.st_mode)) {
    throw ToolError(path + ": is a directory, not a bag");
  }
  std::ifstream probe(path, std::ios::binary);
  if (!probe) {
    const int error = errno;
    // A shell passes a pattern that matches no file on as it is (bash without nullglob).
    const bool pattern = error == ENOENT && path.find_first_of("*?[") != std::string::npos;
    throw ToolError(path + ": cannot open (" + std::strerror(error) + ")" +
                    (pattern ? "; a pattern that matched no file" : ""));
  }
  probe.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(probe.tellg());
  probe.close();
  checkBagStructure(path);
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagUnindexedException&) {
    throw ToolError(path +
                    ": the bag is unindexed (a recording that did not end cleanly); "
                    "`rosbag reindex " +
                    path + "` rebuilds its index");
  } catch (const rosbag::BagException& e) {
    throw ToolError(path + ": not a readable bag, truncated or damaged (" + e.what() + ", " +
                    std::to_string(size) +
                    " bytes); `rosbag reindex` may recover a truncated "
                    "recording");
  }
}

namespace {

/// The topic's name as recorded in `bag` ("imu" may be recorded as "/imu").
std::string recordedName(rosbag::Bag& bag, const std::string& topic) {
  rosbag::View view(bag);
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (c->topic == topic) return topic;
  }
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    if (sameTopic(c->topic, topic)) return c->topic;
  }
  return topic;
}

rosbag::TopicQuery queryIn(rosbag::Bag& bag, const std::vector<std::string>& topics) {
  std::vector<std::string> names;
  for (const auto& t : topics) names.push_back(recordedName(bag, t));
  return rosbag::TopicQuery(names);
}

std::string seconds(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%.1f s", s);
  return text;
}

}  // namespace

BagSet::BagSet(const std::vector<std::string>& paths) : paths_(paths) {
  for (std::size_t i = 0; i < paths.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      struct stat a {};
      struct stat b {};
      const bool same = ::stat(paths[i].c_str(), &a) == 0 && ::stat(paths[j].c_str(), &b) == 0 &&
                        a.st_dev == b.st_dev && a.st_ino == b.st_ino;
      if (same) {
        throw UsageError(paths[i] + ": given twice (the same file as " + paths[j] +
                         "); each input is read once");
      }
    }
  }
  for (const auto& path : paths) {
    bags_.push_back(std::make_unique<rosbag::Bag>());
    openBag(*bags_.back(), path);
  }
}

std::string BagSet::name() const {
  std::string text;
  for (const auto& p : paths_) text += (text.empty() ? "" : ", ") + p;
  return text;
}

void BagSet::addQuery(rosbag::View& view, const std::vector<std::string>& topics) {
  for (auto& bag : bags_) view.addQuery(*bag, queryIn(*bag, topics));
}

std::vector<std::string> BagSet::overlaps(const std::vector<std::string>& topics) {
  struct Span {
    ros::Time begin, end;
    bool any;
  };
  std::vector<Span> spans;
  for (auto& bag : bags_) {
    rosbag::View view(*bag, queryIn(*bag, topics));
    spans.push_back({view.getBeginTime(), view.getEndTime(), view.size() > 0});
  }
  std::vector<std::string> found;
  for (std::size_t i = 0; i < spans.size(); ++i) {
    for (std::size_t j = i + 1; j < spans.size(); ++j) {
      if (!spans[i].any || !spans[j].any) continue;
      const ros::Time from = std::max(spans[i].begin, spans[j].begin);
      const ros::Time to = std::min(spans[i].end, spans[j].end);
      // Split parts touch at most at one record time (a message on each side of the cut).
      if (to > from) {
        found.push_back(paths_[i] + " and " + paths_[j] + " share " + seconds((to - from).toSec()));
      }
    }
  }
  return found;
}

std::string describeTopics(BagSet& bags) {
  std::set<std::string> topics;
  for (std::size_t i = 0; i < bags.size(); ++i) {
    rosbag::View view(bags.bag(i));
    for (const rosbag::ConnectionInfo* c : view.getConnections()) {
      topics.insert(c->topic + " (" + c->datatype + ")");
    }
  }
  std::string text;
  for (const auto& t : topics) text += (text.empty() ? " " : ", ") + t;
  return topics.empty() ? std::string(" no topics") : text;
}

std::optional<std::string> topicType(BagSet& bags, const std::string& topic) {
  std::optional<std::string> type;
  for (std::size_t i = 0; i < bags.size(); ++i) {
    rosbag::View view(bags.bag(i), queryIn(bags.bag(i), {topic}));
    for (const rosbag::ConnectionInfo* c : view.getConnections()) {
      if (type && *type != c->datatype) {
        throw ToolError(topic + ": carries more than one type (" + *type + ", " + c->datatype +
                        ")");
      }
      type = c->datatype;
    }
  }
  return type;
}

std::string requireTopic(BagSet& bags, const std::string& topic, const char* role,
                         const std::vector<std::pair<std::string, std::string>>& accepted) {
  std::string names;
  for (const auto& a : accepted) names += (names.empty() ? "" : " or ") + a.first;
  std::optional<std::string> found;
  for (std::size_t i = 0; i < bags.size(); ++i) {
    rosbag::View view(bags.bag(i), queryIn(bags.bag(i), {topic}));
    for (const rosbag::ConnectionInfo* c : view.getConnections()) {
      const bool ok = std::any_of(accepted.begin(), accepted.end(), [c](const auto& a) {
        return a.first == c->datatype && a.second == c->md5sum;
      });
      if (!ok) {
        throw ToolError(bags.paths()[i] + ": " + role + " topic '" + c->topic + "' carries " +
                        c->datatype + " (md5 " + c->md5sum + "); accepted: " + names);
      }
      found = c->datatype;
    }
  }
  if (!found) {
    throw ToolError(bags.name() + ": no " + role + " topic '" + topic + "' (" + names +
                    "); the bag" + (bags.size() > 1 ? "s have" : " has") + ":" +
                    describeTopics(bags));
  }
  if (messageCount(bags, {topic}) == 0) {
    throw ToolError(bags.name() + ": " + role + " topic '" + topic + "' has no messages");
  }
  return *found;
}

std::uint64_t messageCount(BagSet& bags, const std::vector<std::string>& topics) {
  std::uint64_t n = 0;
  for (std::size_t i = 0; i < bags.size(); ++i) {
    n += rosbag::View(bags.bag(i), queryIn(bags.bag(i), topics)).size();
  }
  return n;
}

}  // namespace tools
}  // namespace attitude_propagator
