"""Children that stay where they are drawn when their parent goes."""


def follow(child, parent):
    """Makes `child` a child of `parent` drawn in the parent's space (its data in the parent's object space).

    The parent's current transform goes into the child's own transform and its inverse into the parent inverse,
    as Blender's Object (Keep Transform) parenting does: while the parent lives, the child is drawn with it
    (parent · parent⁻¹ · parent), and when the user deletes the parent (Blender then drops the parent's
    transform) the child stays where it was drawn instead of jumping to the origin. Call it after the parent's
    transform is set."""
    placed = parent.matrix_world.copy()
    child.parent = parent
    child.matrix_parent_inverse = placed.inverted()
    child.matrix_basis = placed
