"""The command floor: what the ``mt-accuracy`` command (``cli.py``) runs.

Each command module declares its subcommands with ``add_parser(commands)`` - their
options, their validator (``validate``: every option checked before any work) and their
handler - and raises the package's errors; ``cli.py`` only assembles them.

bags         info (what a bag holds) and recover (a damaged bag's closed chunks)
record       topics to a bag, by the recorder node
play         a bag's messages in recorded time, by the player node
simulate     a scenario on the virtual machine tool, to a bag and CSV files
check        the model-versus-measurement workbench on a survey or a bag
check_log    the same on a thermal log
check_result what check found (typed), printed and as JSON
demo         the main job: the virtual machine tool through the full graph
fleet        many machines' bags and surveys on Dask
iso230       ISO 230-2 figures of a laser interferometer's runs
model_tools  models: add effects, set a node's model, list versions
rotary_tools the ball bar, the probe (rotary axes) and the CNC tables
topic_tools  topics: echo, hz, list (no ``ros2`` CLI on PyPI)
processes    start nodes as processes (a small stand-in for ros2 launch)
check_timing whether the live checks kept up with the data
"""
