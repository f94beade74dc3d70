"""nfmr: double-loop sliding-mode trajectory tracking for 4WIS robots (Zhang et al. 2023).

Layers (imports go one way only):

- core math, ROS-free: angles, validation, gains, sliding_functions, outer_loop, inner_loop,
  saturation, dlsmc, trajectories, steering, disturbances, kinematic_sim, batch_sim,
  metrics, params, tracking_session, loop_stats, bag_writer, bag_reader, bag_reindex,
  worker_pool, cli_common;
- the in-process pybullet plant (pybullet_plant, over nfmr_sim's world; no ROS);
- ROS nodes and tools (rclpy, messages): controller_node, recorder_node, ros_parameters,
  node_main, run_analysis, launcher, replay_cli, analyze_cli, bench_ros; and the command
  lines eval_cli, montecarlo_cli, tune_cli, reindex_cli, compare_cli, baseline_tuning,
  benchmarks.
"""
