import mi_voldis  # noqa: F401  (selects the Mitsuba variant and registers the plugins before any test)
