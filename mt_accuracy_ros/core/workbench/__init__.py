"""Model versus measurement: where the model fails and which effect is missing.

* ``diagnosis``  reference surveys of the TCP error (laser, probe, ball bar)
                 against the error model: residuals, candidate effects ranked by
                 time-blocked cross-validation, adding the one found.
* ``tabular``    the same loop on tabular logs (CSV): a linear thermal model of
                 named inputs (Zhu eq. 3.12).
"""
