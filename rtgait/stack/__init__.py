"""One control tick: estimator -> walking controller -> whole-body IK -> joint command."""
