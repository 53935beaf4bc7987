//! `palpus run --set KEY=VALUE`: one value of a scene file replaced for one run.

/// One `KEY=VALUE` replacing a value of a scene file (`task.depth_m=0.026`): a dotted key
/// into its tables and a TOML value (strings quoted).
#[derive(Debug, Clone, PartialEq)]
pub struct SceneOverride {
    /// The dotted key.
    pub key: String,
    /// The value it takes.
    pub value: toml::Value,
}

impl std::str::FromStr for SceneOverride {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let (key, value) = text
            .split_once('=')
            .ok_or_else(|| format!("`{text}`: expected KEY=VALUE, such as task.depth_m=0.026"))?;
        let key = key.trim();
        if key.is_empty() || key.split('.').any(str::is_empty) {
            return Err(format!(
                "`{text}`: the key must be dotted names, such as task.depth_m"
            ));
        }
        let value = toml::from_str::<toml::Table>(&format!("value = {}", value.trim()))
            .ok()
            .and_then(|mut t| t.remove("value"))
            .ok_or_else(|| {
                format!("`{text}`: the value is not a TOML value (quote a string: key=\"text\")")
            })?;
        Ok(Self {
            key: key.to_owned(),
            value,
        })
    }
}

impl SceneOverride {
    /// Sets the value in `table`, making the tables on its way where missing.
    pub(super) fn apply(&self, table: &mut toml::Table) -> Result<(), String> {
        let mut names: Vec<&str> = self.key.split('.').collect();
        let last = names.pop().unwrap_or_default();
        let mut at = table;
        for (i, name) in names.iter().enumerate() {
            let entry = at
                .entry((*name).to_owned())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            at = entry
                .as_table_mut()
                .ok_or_else(|| format!("`{}` is not a table", names[..=i].join(".")))?;
        }
        at.insert(last.to_owned(), self.value.clone());
        Ok(())
    }
}
