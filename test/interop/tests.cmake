# Test suites of src/interop.
