"""What passes between body, controller and task: genome layouts, the contract a component declares, mapping controller
outputs onto actions, the mirrored stance frame, the input normaliser."""
