"""Model versus measurement: where the model fails and which effect is missing.

* ``diagnosis``  reference surveys of the TCP error (laser, probe, ball bar)
                 against the error model: residuals, the verdict, adding what
                 was named.
* ``selection``  forward selection over the effect catalogue, time-blocked CV
                 with in-fold hyperparameters, a held-out stop rule.
* ``localisation`` where the residual lives: variance shares per variable,
                 periodograms, the plain sentence.
* ``tabular``    the same loop on tabular logs (CSV): a linear thermal model of
                 named inputs (Zhu eq. 3.12).
"""
