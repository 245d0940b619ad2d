"""What the generated kernels import: sin and cos (`trig`), and the linear solvers (`linear_solvers`)."""
