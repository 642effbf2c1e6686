#include "attitude_propagator/ros/hand_over_bound.h"

#include <ros/poll_manager.h>

namespace attitude_propagator {

IoRoundsListener::IoRoundsListener(IoRounds& rounds)
    : connection_(
          ros::PollManager::instance()->addPollThreadListener([&rounds] { rounds.ranOnce(); })) {
}  // on roscpp's I/O thread, once per round

IoRoundsListener::~IoRoundsListener() {
  // Waits for a call in progress (the poll thread holds the signal's lock while it calls).
  ros::PollManager::instance()->removePollThreadListener(connection_);
}

}  // namespace attitude_propagator
