"""Light transport (thesis ch. 8-9): meshes, BVH, scenes, integrators and the render driver."""
