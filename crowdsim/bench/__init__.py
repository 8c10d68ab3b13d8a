"""The benchmarks of ``crowdsim bench``: the hot parts and the whole loop (``parts``), the crowd beside JuPedSim
(``sim``), every sensor (``sensors``) and the evaluation (``eval``)."""
