"""ROS-free numerical core: numpy and scipy only, importable without rclpy.

One subpackage per domain a metrologist knows:

``scales``        dual linear scales: yaw, kNN systematic error, streaming,
                  repeatability/ISO 230-2, uncertainty, deterioration (Kidani).
``kinematics``    HTMs, machine descriptions, error functions, the kinematic
                  error chain (Kidani ch. 2, Khan & Chen, Zhu App. A).
``thermal``       FE heat conduction and modal analysis, regression models,
                  thermal links, sensor placement (Zhu ch. 3-4, Krulewich).
``compensation``  the volumetric error model the nodes run and the CNC
                  compensation tables built from it.
``effects``       the open effect catalogue (geometric, rotary, thermal,
                  motion, cross-axis, user-defined), the variables effects
                  read, safe expressions.
``workbench``     model versus measurement: where the residual lives, which
                  effects are missing (reference surveys and tabular logs).

``errors`` and ``validation`` are shared by all of them.
"""
