"""Add Snow Layer: the operators that make and remake snow, and their panels."""
