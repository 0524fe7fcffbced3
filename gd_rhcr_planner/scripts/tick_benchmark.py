#!/usr/bin/env python3
"""Prints tick latency percentiles of a running gd_rhcr_planner from `planner_stats`.

    rosrun gd_rhcr_planner tick_benchmark.py _duration:=60
e.g. against `roslaunch gd_rhcr_planner warehouse_sim.launch rviz:=false num_robots:=500`
(the 500-robot, 2 Hz warehouse target: no overruns, tick callback well under 0.5 s).
It needs a running planner: start one first, e.g. `bash scripts/run_warehouse.sh` (which builds
everything) or, after `bash scripts/ros_build.sh && source .ws/devel/setup.bash`,
`roslaunch gd_rhcr_planner warehouse_sim.launch rviz:=false`.
"""
import sys

import rosgraph
import rospy

from gd_rhcr_msgs.msg import PlannerStats


def pct(values, q):
    v = sorted(values)
    return v[min(len(v) - 1, int(round(q / 100.0 * (len(v) - 1))))] if v else float("nan")


START_FIRST = ("start a planner first: bash scripts/run_warehouse.sh, or roslaunch gd_rhcr_planner "
               "warehouse_sim.launch rviz:=false (after bash scripts/ros_build.sh && source .ws/devel/setup.bash)")


def main():
    if not rosgraph.is_master_online():
        print("tick_benchmark: no ROS master at %s; %s" % (rosgraph.get_master_uri(), START_FIRST))
        sys.exit(1)
    rospy.init_node("tick_benchmark", anonymous=True)
    duration = rospy.get_param("~duration", 30.0)
    stats = []
    rospy.Subscriber("planner_stats", PlannerStats, stats.append, queue_size=1000)
    rospy.loginfo("collecting planner_stats for %.0f s", duration)
    rospy.sleep(duration)
    if not stats:
        print("tick_benchmark: no planner_stats received in %.0f s; %s" % (duration, START_FIRST))
        sys.exit(1)
    step = [s.step_time for s in stats]
    plan = [s.plan_time for s in stats]
    last = stats[-1]
    print("planner %s, %d robots, %d ticks, period %.3f s" % (last.planner, last.num_robots, len(stats), last.tick_period))
    for name, v in (("tick callback", step), ("plan time", plan)):
        print("%-14s p50 %.4f  p90 %.4f  p99 %.4f  max %.4f s" % (name, pct(v, 50), pct(v, 90), pct(v, 99), max(v)))
    print("overruns %d (in this window %d), skipped ticks %d, delivered %d, failed %d" % (
        last.overruns, last.overruns - stats[0].overruns, last.skipped_ticks, last.tasks_delivered, last.tasks_failed))


if __name__ == "__main__":
    main()
