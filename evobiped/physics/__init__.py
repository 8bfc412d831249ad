"""MuJoCo's side: the MJCF loader, batches of simulations, the gait senses' tracker, perturbations."""
