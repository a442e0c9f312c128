"""Monte Carlo and quasi-Monte Carlo (thesis ch. 5-7, app. A and C): samplers, warps, estimators."""
