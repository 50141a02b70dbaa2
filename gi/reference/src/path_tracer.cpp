// Placeholder until the path tracer lands (issue 4).
