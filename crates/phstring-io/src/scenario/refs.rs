//! Node references (`node`, `path`, `between` keys): a mesh node index, `"NAME"` of a
//! `[[node]]`, `"STRING:INDEX"`, the INDEX-th node along a string's path, or
//! `"BODY.POINT"`, a point of a rigid body; and their resolution to mesh nodes, with messages
//! that say what exists.

use std::collections::HashMap;
use std::ops::Range;

use serde::{Deserialize, Serialize};
use toml::Spanned;

use super::{ScenarioError, ScenarioFile};
use crate::text::clip;

/// A reference to a node, as written in a scenario.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
#[serde(untagged)]
pub enum NodeRef {
    /// A mesh node index; negative values count from the end (`-1` is the last node). In a
    /// network, nodes are numbered as [`phstring::NetworkBuilder`] numbers them: the
    /// `[[node]]`s in file order, then the interior nodes of each string in file order,
    /// then the fixed ends of springs with `to_point`.
    Index(i64),
    /// `"NAME"` of a `[[node]]`, `"STRING:INDEX"`: node INDEX along string STRING's path
    /// (0 is its first node; negative values count from its last node, `-1`), or
    /// `"BODY.POINT"`: point POINT of the rigid body `[bodies.BODY]`.
    Name(String),
}

impl<'de> Deserialize<'de> for NodeRef {
    fn deserialize<De: serde::Deserializer<'de>>(d: De) -> Result<Self, De::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = NodeRef;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(
                    "a node: an index (integer), a [[node]] name or \"STRING:INDEX\" (string)",
                )
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<NodeRef, E> {
                Ok(NodeRef::Index(v))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<NodeRef, E> {
                i64::try_from(v)
                    .map(NodeRef::Index)
                    .map_err(|_| E::custom(format!("node index {v} is too large")))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<NodeRef, E> {
                Ok(NodeRef::Name(v.to_string()))
            }
        }
        d.deserialize_any(Visitor)
    }
}

impl std::fmt::Display for NodeRef {
    /// An index as written, a name in double quotes (clipped).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NodeRef::Index(i) => write!(f, "{i}"),
            NodeRef::Name(n) => write!(f, "\"{}\"", clip(n)),
        }
    }
}

/// The nodes along one string: its path nodes, with `per_span − 1` interior nodes between
/// two consecutive ones, numbered consecutively from `first_interior` span by span (as
/// [`phstring::NetworkBuilder::string`] creates them).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Along {
    /// Mesh nodes of the path.
    pub path: Vec<usize>,
    /// Elements per span.
    pub per_span: usize,
    /// Mesh index of the first interior node.
    pub first_interior: usize,
}

impl Along {
    /// Number of nodes along the string.
    pub fn len(&self) -> usize {
        (self.path.len() - 1) * self.per_span + 1
    }
    /// Mesh index of node `k` along the string (`k < len()`).
    pub fn node(&self, k: usize) -> usize {
        let (span, off) = (k / self.per_span, k % self.per_span);
        if off == 0 {
            self.path[span]
        } else {
            self.first_interior + span * (self.per_span - 1) + off - 1
        }
    }
    /// Mesh indices of the interior nodes.
    pub fn interior(&self) -> Range<usize> {
        let n = (self.path.len() - 1) * (self.per_span - 1);
        self.first_interior..self.first_interior + n
    }
}

/// What node references resolve against: the mesh size, the named nodes and the strings
/// known so far.
#[derive(Debug, Default)]
pub(super) struct Nodes<'s> {
    /// Nodes of the mesh (so far, while strings are added).
    pub n_nodes: usize,
    /// Whether strings are still being added (messages then say "so far").
    pub partial: bool,
    named: HashMap<&'s str, usize>,
    /// Names in file order, for messages.
    names: Vec<&'s str>,
    strings: HashMap<&'s str, usize>,
    along: Vec<Along>,
    /// Names of all `[[string]]`s in file order, for messages.
    string_names: Vec<&'s str>,
    /// The bodies' points `(point name, mesh node)`, by body name (`"BODY.POINT"`).
    bodies: HashMap<&'s str, Vec<(&'s str, usize)>>,
    /// Body names in file order, for messages.
    body_names: Vec<&'s str>,
}

impl<'s> Nodes<'s> {
    /// A chain of `n_nodes` nodes without names (a single string).
    pub fn chain(n_nodes: usize) -> Self {
        Self {
            n_nodes,
            ..Self::default()
        }
    }
    /// Starts a network whose strings are named `string_names` (file order).
    pub fn network(string_names: Vec<&'s str>) -> Self {
        Self {
            partial: true,
            string_names,
            ..Self::default()
        }
    }
    /// Adds the named node `name` with mesh index `node`.
    pub fn add_named(&mut self, name: &'s str, node: usize) {
        self.named.insert(name, node);
        self.names.push(name);
    }
    /// The mesh node named `name`.
    pub fn named(&self, name: &str) -> Option<usize> {
        self.named.get(name).copied()
    }
    /// Adds a string.
    pub fn add_string(&mut self, name: &'s str, along: Along) {
        self.strings.insert(name, self.along.len());
        self.along.push(along);
    }
    /// The nodes along string `name`.
    pub fn string(&self, name: &str) -> Option<&Along> {
        self.strings.get(name).map(|&g| &self.along[g])
    }
    /// Adds body `name` with its points `(point name, mesh node)`.
    pub fn add_body(&mut self, name: &'s str, points: Vec<(&'s str, usize)>) {
        self.bodies.insert(name, points);
        self.body_names.push(name);
    }
}

/// Node `raw` of a mesh of `n_nodes` nodes, negative indices counting from the end (`-1` is
/// the last node); `None` if out of range.
pub(super) fn resolve_index(raw: i64, n_nodes: usize) -> Option<usize> {
    let node = if raw < 0 {
        (n_nodes as i64).checked_add(raw)?
    } else {
        raw
    };
    usize::try_from(node).ok().filter(|&n| n < n_nodes)
}

/// The INDEX of `"STRING:INDEX"`: ASCII digits with an optional leading `-`, nothing else
/// (no blanks, no `+`: `"s1:+1"` or `"s1: 1"` may be a typo for another reference, and a
/// node reference has one spelling).
fn along_index(text: &str) -> Option<i64> {
    let digits = text.strip_prefix('-').unwrap_or(text);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    text.parse().ok()
}

/// Most names listed in a message about an unknown name.
const LISTED: usize = 8;

/// `names` for a message about the unknown `wanted`: the closest (by edit distance) first,
/// at most [`LISTED`], e.g. `platform, corner0, …; 5 in all`.
pub(super) fn known(names: &[&str], wanted: &str) -> String {
    if names.is_empty() {
        return "none".into();
    }
    // Edit distances of the first 10000 names only: a message, not a search engine.
    let mut ranked: Vec<(usize, usize)> = names
        .iter()
        .take(10_000)
        .enumerate()
        .map(|(i, n)| (edit_distance(n, wanted), i))
        .collect();
    ranked.sort_unstable();
    let mut text: Vec<String> = ranked
        .iter()
        .take(LISTED)
        .map(|&(_, i)| clip(names[i]).into_owned())
        .collect();
    if names.len() > LISTED {
        text.push(format!("…; {} in all", names.len()));
    }
    text.join(", ")
}

/// Levenshtein distance over characters, both texts cut after 64 characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().take(64).collect();
    let b: Vec<char> = b.chars().take(64).collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// A node for messages: `node 5` for an index, `"platform" (node 0)` for a name.
pub(super) fn label(r: &NodeRef, node: usize) -> String {
    match r {
        NodeRef::Index(_) => format!("node {node}"),
        NodeRef::Name(n) => format!("\"{}\" (node {node})", clip(n)),
    }
}

impl ScenarioFile {
    /// The mesh node that `r` (the value of `key`) refers to, or an error naming `key`.
    pub(super) fn resolve(
        &self,
        key: &str,
        r: &Spanned<NodeRef>,
        nodes: &Nodes,
    ) -> Result<usize, ScenarioError> {
        let err = |reason: String| self.invalid(key, r.span(), reason);
        let so_far = if nodes.partial { " so far" } else { "" };
        match r.get_ref() {
            NodeRef::Index(raw) => resolve_index(*raw, nodes.n_nodes).ok_or_else(|| {
                err(match nodes.n_nodes {
                    0 => format!("= {raw} is out of range: there are no nodes{so_far}"),
                    n => format!(
                        "= {raw} is out of range: the mesh has nodes 0..={}{so_far} (or -1..=-{n} from the end)",
                        n - 1
                    ),
                })
            }),
            NodeRef::Name(name) => match name.rsplit_once(':') {
                None if name.contains('.') => self.body_point(name, nodes).map_err(err),
                None => nodes.named(name).ok_or_else(|| {
                    err(if nodes.names.is_empty() {
                        format!(
                            "names node \"{}\", but the scenario has no [[node]] tables (a node index is an integer)",
                            clip(name)
                        )
                    } else {
                        format!(
                            "names node \"{}\", which is not a [[node]] (known: {})",
                            clip(name),
                            known(&nodes.names, name)
                        )
                    })
                }),
                Some((string, index)) => {
                    let Some(k) = along_index(index) else {
                        return Err(err(format!(
                            "= \"{}\": after the ':' comes a node index along the string, e.g. \"{}:3\" or \"{}:-1\" (digits with an optional leading '-', no blanks or '+')",
                            clip(name),
                            clip(string),
                            clip(string)
                        )));
                    };
                    let Some(along) = nodes.string(string) else {
                        return Err(err(if nodes.string_names.contains(&string) {
                            format!(
                                "names string \"{}\", which is not defined above this one: a string's path can use [[node]]s and the nodes of the strings above it",
                                clip(string)
                            )
                        } else {
                            format!(
                                "names string \"{}\", which is not a [[string]] (known: {})",
                                clip(string),
                                known(&nodes.string_names, string)
                            )
                        }));
                    };
                    let n = along.len();
                    resolve_index(k, n).map(|k| along.node(k)).ok_or_else(|| {
                        err(format!(
                            "= \"{}\" is out of range: string {} has nodes 0..={} (or -1..=-{n} from the end)",
                            clip(name),
                            clip(string),
                            n - 1
                        ))
                    })
                }
            },
        }
    }
}

impl ScenarioFile {
    /// The mesh node of body point `"BODY.POINT"` (`name`), or why there is none.
    fn body_point(&self, name: &str, nodes: &Nodes) -> Result<usize, String> {
        let (body, point) = name.split_once('.').unwrap_or((name, ""));
        let Some(points) = nodes.bodies.get(body) else {
            return Err(if nodes.body_names.is_empty() {
                format!(
                    "names body point \"{}\", but the scenario has no [bodies.NAME] tables (\"BODY.POINT\" names a point of a rigid body)",
                    clip(name)
                )
            } else {
                format!(
                    "names body point \"{}\", but \"{}\" is not a [bodies.NAME] table (known: {})",
                    clip(name),
                    clip(body),
                    known(&nodes.body_names, body)
                )
            });
        };
        match points.iter().find(|(p, _)| *p == point) {
            Some(&(_, node)) => Ok(node),
            None => {
                let names: Vec<&str> = points.iter().map(|(p, _)| *p).collect();
                Err(format!(
                    "names body point \"{}\", but body \"{}\" has no point \"{}\" (its points: {})",
                    clip(name),
                    clip(body),
                    clip(point),
                    known(&names, point)
                ))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodes_along_a_string_follow_the_builder_numbering() {
        // Path 7 → 2 → 9, 3 elements per span, interior nodes from 20: 7, 20, 21, 2, 22,
        // 23, 9.
        let a = Along {
            path: vec![7, 2, 9],
            per_span: 3,
            first_interior: 20,
        };
        let all: Vec<usize> = (0..a.len()).map(|k| a.node(k)).collect();
        assert_eq!(all, [7, 20, 21, 2, 22, 23, 9]);
        assert_eq!(a.interior(), 20..24);
        assert_eq!(resolve_index(-1, 7), Some(6));
        assert_eq!(resolve_index(-8, 7), None);
        assert_eq!(resolve_index(i64::MIN, 7), None);
        assert_eq!(resolve_index(7, 7), None);
    }

    /// A node index along a string has one spelling: `"s1:+1"`, `"s1: 1"`, `"s1:1 "` and
    /// `"s1:--1"` are refused, `"s1:1"`, `"s1:-1"` and `"s1:007"` are read.
    #[test]
    fn along_index_is_digits_with_an_optional_minus() {
        assert_eq!(along_index("1"), Some(1));
        assert_eq!(along_index("-1"), Some(-1));
        assert_eq!(along_index("007"), Some(7));
        for bad in ["+1", " 1", "1 ", "--1", "-", "", "1e2", "0x1", "١"] {
            assert_eq!(along_index(bad), None, "{bad:?}");
        }
        // Too many digits for an i64: refused, not wrapped.
        assert_eq!(along_index("99999999999999999999"), None);
    }

    #[test]
    fn unknown_names_list_the_closest_first() {
        let names = ["corner0", "corner1", "platform", "corner2"];
        assert!(known(&names, "platfrom").starts_with("platform, "));
        let many: Vec<String> = (0..20).map(|i| format!("n{i}")).collect();
        let many: Vec<&str> = many.iter().map(String::as_str).collect();
        assert!(known(&many, "n7").ends_with("…; 20 in all"));
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }
}
