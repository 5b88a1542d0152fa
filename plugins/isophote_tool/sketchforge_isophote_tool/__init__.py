"""(see plugin.py)"""
