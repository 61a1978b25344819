//! Graph algorithms over node children, shared by the scene and the file readers.

/// Finds a cycle in a directed graph of `count` nodes whose edges are given by
/// `child(node, i)` (the `i`-th child of `node`, `None` past the last). Returns the edge
/// `(node, child)` that closes the first cycle found. Iterative three-colour DFS: no recursion,
/// so deep hierarchies cannot overflow the stack. Children must be `< count`.
pub fn first_cycle(
    count: usize,
    child: impl Fn(usize, usize) -> Option<usize>,
) -> Option<(usize, usize)> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        OnPath,
        Done,
    }
    let mut marks = vec![Mark::New; count];
    let mut stack: Vec<(usize, usize)> = Vec::new();
    for start in 0..count {
        if marks[start] != Mark::New {
            continue;
        }
        marks[start] = Mark::OnPath;
        stack.push((start, 0));
        while let Some((node, next)) = stack.last_mut() {
            let node = *node;
            match child(node, *next) {
                Some(c) => {
                    *next += 1;
                    match marks[c] {
                        Mark::OnPath => return Some((node, c)),
                        Mark::New => {
                            marks[c] = Mark::OnPath;
                            stack.push((c, 0));
                        }
                        Mark::Done => {}
                    }
                }
                None => {
                    marks[node] = Mark::Done;
                    stack.pop();
                }
            }
        }
    }
    None
}
