"""tissuemech.fem: the complete half (scikit-fem, axisymmetric finite strain, mixed u-p).

Slow but complete: it calibrates and checks the reduced models. Imports only the shared
constitutive leaf ``reduced.material`` from the reduced half.
"""
