"""Hypothesis profiles: bounded example counts in CI, longer runs on request.

`pytest --hypothesis-profile=long` runs 20x the examples; CI uses the default.
"""

from hypothesis import HealthCheck, settings

settings.register_profile("default", max_examples=60, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("long", max_examples=1200, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("default")
