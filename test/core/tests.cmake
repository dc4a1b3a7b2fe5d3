# Test suites of src/core.
