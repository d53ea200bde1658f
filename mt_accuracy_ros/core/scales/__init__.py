"""Dual linear scales: what two parallel scales on one axis tell about that axis.

* ``dual_scale``     yaw E_C = (x2 - x1)/D and its error terms (Kidani eq. 2.13,
                     2.20-2.21, 3.1-3.4, 3.17).
* ``knn``            exact 1-D kNN regression with K-fold CV of k (Kidani eqs. 4.10-4.12).
* ``streaming``      the same, bounded in memory, for a live node.
* ``repeatability``  systematic/random split at repeated positions (Kidani eqs. 2.22-2.23),
                     ISO 230-2 figures.
* ``uncertainty``    type B budget of the yaw (Table 3.4, Kidani eq. 3.10).
* ``deterioration``  alarm and command compensation (Kidani eqs. 2.1-2.2, 3.11-3.16).
* ``yaw_diagnosis``  the scale pair's effects on its yaw against a reference yaw
                     (Kidani eqs. 2.20, 3.5, 3.17), ranked by the workbench.
"""
