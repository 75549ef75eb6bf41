"""Learning-augmented frontier exploration (LFE): frontier properties and the Bellman planner.

``properties`` computes the ground-truth frontier properties (R_A, D_in, D_out) from a partial map
and the true map: the oracle of the paper's ablation and the targets for a learned estimator;
``tour`` splits the closed tour of a region's key nodes into D_in and D_out for it.
``bellman`` chooses a frontier from those properties with the paper's recursion (Eq. 4, 5).

Nothing is re-exported here on purpose: ``bellman`` needs only numpy/scipy/skimage, while
``properties`` also needs networkx (through ``tour``), and importing the planner should not pull that in.
"""
