"""The viewer's tests (a package: test_script_inputs shares test_controller's scene)."""
