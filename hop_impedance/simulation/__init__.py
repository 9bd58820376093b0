"""Forward-dynamics hopping simulator: the source of simulated recordings with known truth.

Entry points
------------
- :func:`hop_impedance.simulation.simulate.simulate_recording` -- high-level
  choices -> (contract ``Recording``, truth dict); ``write_simulated_recording``
  writes ``REC.mcap`` + ``REC.truth.json``.
- :func:`hop_impedance.simulation.stance.simulate_stance` -- one stance forward
  from a touchdown state with any law and surface (for the discovery workflow).
- :func:`hop_impedance.simulation.hopping_trial.simulate_hopping` -- continuous
  hopping (stance integration, ballistic flight, hop sequencing).
- Modules: ``dynamics`` (equations of motion), ``ground`` (surface laws),
  ``impedance_laws`` (Eq. 3, activation, push-off), ``sensors``, ``truth``,
  ``scenarios`` (seed Table 2 magnitudes and the effect switches).
"""
