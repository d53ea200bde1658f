"""Model versus measurement: where the model fails and which effect is missing.

* ``diagnosis``  reference surveys of the TCP error (laser, probe, ball bar)
                 against the error model: residuals, the verdict, adding what
                 was named.
* ``selection``  forward selection over the effect catalogue, time-blocked CV
                 (or forward validation for logs) with in-fold hyperparameters and
                 ridge strengths, a held-out test per component the effect moves.
* ``localisation`` where the residual lives: variance shares per variable,
                 periodograms, the plain sentence.
* ``thermal_log`` a thermal log (CSV: one displacement, temperatures, a spindle)
                 as a survey of a standing machine, on the same engine.
* ``regimes``    a log's operating regimes from its data (runs, heating, dwell,
                 cooling, spindle programs) and how far inputs leave their
                 training range.
* ``walk_forward`` a log replayed in time: each period predicted by a fit on
                 every row before it.
"""
