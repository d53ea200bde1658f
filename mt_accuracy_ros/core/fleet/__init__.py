"""A fleet's history, ROS-free and Dask-free.

:mod:`.trends`: each machine's model-versus-measurement error over its days, the
drift in it (a least-squares trend against its standard error), the ranking of
the machines by it, and the effects many machines share. Plain numbers in,
plain numbers out: ``mt-accuracy fleet`` gathers them from its workers.
"""
