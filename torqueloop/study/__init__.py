# SPDX-License-Identifier: MIT
"""The studies: the applications that run the simulations and the method
end to end and write a report, beside the lab tool (torqueloop.cli; neither
imports the other).

    experiment        - the paper's experiment and its title question (make run)
    characterization  - the characterisation method on the simulated bench, with
                        repeatability, linearity and each plant effect off (make characterize)
    characterize_cli  - the characterisation command with the study's sim (torqueloop/characterize/command.py has the rest)
    cli               - ``torqueloop-study experiment|characterize``

A study takes objects, never a command line: an
:class:`~torqueloop.study.experiment.ExperimentPlan`, a
:class:`~sim_models.variants.PlantSpec` parsed once at the edge
(:func:`sim_models.variants.plant_of`).
"""
