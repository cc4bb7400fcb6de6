"""The Rerun viewer: recordings, their blueprint and the plain geometry they draw.
"""
