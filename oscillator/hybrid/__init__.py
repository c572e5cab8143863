"""The hybrid simulation: the supervisor (the only stateful part), what a run records, the guards that
stop a run that would not end, the typed result, and :func:`simulate`."""
