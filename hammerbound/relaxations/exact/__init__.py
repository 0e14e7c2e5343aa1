"""The exact method's machinery (private): branch-and-bound, OBBT, McCormick node LPs,
verified points, the local walk and working sets. Use :func:`hammerbound.relaxations.exact_bounds`."""
