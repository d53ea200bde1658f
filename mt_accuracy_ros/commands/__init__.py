"""The command floor: what the ``mt-accuracy`` command (``cli.py``) runs.

check        the model-versus-measurement workbench on a survey, a bag or a log
demo         the main job: the virtual machine tool through the full graph
model_tools  models: add effects, set a node's model, list versions
rotary_tools the ball bar and the probe (rotary axes)
topic_tools  topics: echo, hz, list (no ``ros2`` CLI on PyPI)
processes    start nodes as processes (a small stand-in for ros2 launch)
"""
