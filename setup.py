from glob import glob

from setuptools import setup

package_name = "nfmr_dlsmc"

setup(
    name=package_name,
    version="0.1.0",
    packages=["nfmr_dlsmc", "nfmr_sim"],
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{package_name}"]),
        (f"share/{package_name}", ["package.xml"]),
        (f"share/{package_name}/config", glob("config/*.yaml")),
    ],
    python_requires=">=3.10",
    install_requires=[
        "numpy>=1.26,<3",
        "matplotlib>=3.7,<4",
        "scipy>=1.11,<2",
        "pyyaml>=6,<7",
        "pybullet>=3.2.6,<4",
        "mcap>=1.2,<2",
        "ros-jazzy-rclpy>=7.1,<8",
        "ros-jazzy-common-interfaces>=5.3,<6",
        "ros-jazzy-rmw-fastrtps-cpp>=8.4,<9",
    ],
    extras_require={
        "test": ["pytest>=8,<10", "mcap-ros2-support>=0.5,<0.7", "rosbags>=0.10,<0.12",
                 "hypothesis>=6.100,<7"],
        "mutate": ["mutmut>=3.8,<4"],
    },
    zip_safe=True,
    maintainer="nfmr developers",
    maintainer_email="nfmr@example.org",
    description="Double-loop sliding-mode trajectory tracking (Zhang et al., Entropy 2023) "
                "for four-wheel independently steered robots, with a pybullet simulator.",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": [
            "nfmr-eval = nfmr_dlsmc.eval_cli:main",
            "sim = nfmr_sim.sim_node:main",
            "controller = nfmr_dlsmc.controller_node:main",
            "nfmr-run = nfmr_dlsmc.launcher:main",
            "nfmr-analyze = nfmr_dlsmc.analyze_cli:main",
            "nfmr-replay = nfmr_dlsmc.replay_cli:main",
            "nfmr-reindex = nfmr_dlsmc.reindex_cli:main",
            "nfmr-montecarlo = nfmr_dlsmc.montecarlo_cli:main",
            "nfmr-bench = nfmr_dlsmc.benchmarks:main",
            "nfmr-tune = nfmr_dlsmc.tune_cli:main",
            "nfmr-tune-baselines = nfmr_dlsmc.baseline_tuning:main",
            "nfmr-compare = nfmr_dlsmc.compare_cli:main",
        ],
    },
)
