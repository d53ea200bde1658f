"""Install mt_accuracy_ros as an ament_python package (colcon) or with pip."""
from __future__ import annotations

from glob import glob

from setuptools import find_packages, setup

PACKAGE_NAME = "mt_accuracy_ros"

# One table for the entry points so that tests can check package.xml / setup.py
# agreement and the CLI can start every node by name.
NODE_ENTRY_POINTS = {
    "encoder_publisher": "mt_accuracy_ros.nodes.encoder_publisher:main",
    "temperature_publisher": "mt_accuracy_ros.nodes.temperature_publisher:main",
    "yaw_estimator": "mt_accuracy_ros.nodes.yaw_estimator:main",
    "compensation_broadcaster": "mt_accuracy_ros.nodes.compensation_broadcaster:main",
    "model_monitor": "mt_accuracy_ros.nodes.model_monitor:main",
    "recorder": "mt_accuracy_ros.nodes.recorder:main",
    "bag_player": "mt_accuracy_ros.nodes.player:main",
    "foxglove_bridge": "mt_accuracy_ros.nodes.foxglove_bridge:main",
    "cnc_bridge": "mt_accuracy_ros.nodes.cnc_bridge:main",
}

setup(
    name=PACKAGE_NAME,
    version="0.1.0",
    # Only the library: bench/, studies/ and test/ stay in the repository.
    packages=find_packages(include=[PACKAGE_NAME, f"{PACKAGE_NAME}.*"]),
    package_data={PACKAGE_NAME: ["machines/*.yaml", "scenarios/*.yaml", "models/*.yaml",
                                 "templates/*.j2"]},
    data_files=[
        ("share/ament_index/resource_index/packages", [f"resource/{PACKAGE_NAME}"]),
        (f"share/{PACKAGE_NAME}", ["package.xml"]),
        (f"share/{PACKAGE_NAME}/config", glob("config/*.yaml")),
        (f"share/{PACKAGE_NAME}/launch", glob("launch/*.launch.xml")),
        (f"share/{PACKAGE_NAME}/foxglove", glob("foxglove/*.json")),
    ],
    install_requires=["setuptools"],
    zip_safe=True,
    maintainer="mt_accuracy_ros developers",
    maintainer_email="dev@mt-accuracy.invalid",
    description="Live accuracy monitor and volumetric compensation for CNC machine tools.",
    license="Apache-2.0",
    tests_require=["pytest"],
    entry_points={
        "console_scripts": [f"{name} = {target}" for name, target in NODE_ENTRY_POINTS.items()]
        + ["mt-accuracy = mt_accuracy_ros.cli:main"],
    },
)
