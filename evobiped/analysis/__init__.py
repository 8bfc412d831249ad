"""What is asked of walkers once evolved: the robustness battery, choosing a walker, benchmarks."""
