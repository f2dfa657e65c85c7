"""Reading and writing the files occtrack exchanges with users."""
