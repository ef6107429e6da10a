"""Numeric core: reference, HONN, EKF, controllers, metrics. Imports only numpy."""
