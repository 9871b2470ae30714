//! Guards against requests from other sites, and the security headers of
//! every answer (docs/API.md, "Cross-site requests").
//!
//! Every `POST` (the API's only mutating method; others are 405), with or
//! without a token, must
//! - say `Content-Type: application/json` (415 otherwise): neither an HTML
//!   form nor a `no-cors` fetch can, so another site's page cannot send one
//!   without a CORS preflight, which this server never grants;
//! - name in `Host` a host the server answers to (403 otherwise): an IP
//!   address, `localhost` (or a name under `.localhost`), or one of
//!   [`AllowedHosts`] (`serve --allowed-host`). A page whose name was rebound
//!   to the server's address (DNS rebinding) sends its own name;
//! - carry no `Origin`, or one on the request's own host and port or on an
//!   allowed host (403 otherwise; `Origin: null` is refused).
//!
//! Every answer, page, asset or API, carries [`CONTENT_SECURITY_POLICY`]
//! (no framing, scripts only from the server), `X-Content-Type-Options:
//! nosniff` and `Referrer-Policy: no-referrer`.
use crate::error::ApiError;
use crate::spec::FieldError;
use axum::extract::{Request, State};
use axum::http::{HeaderMap, HeaderValue, Method, StatusCode, header};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use std::net::IpAddr;
use std::sync::Arc;

/// The page's policy: everything from the server itself (the bundle embeds
/// three.js and uPlot; Swagger UI is served under `/api/docs/`), images also
/// from `data:` and `blob:` URLs (figures, Swagger UI's icons), inline
/// styles (the charts and Swagger UI set them), no plugins, no framing.
pub const CONTENT_SECURITY_POLICY: &str = "default-src 'self'; script-src 'self'; \
    style-src 'self' 'unsafe-inline'; img-src 'self' data: blob:; font-src 'self' data:; connect-src 'self'; \
    object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'";

/// Host names a `POST` may name besides IP addresses and `localhost`: the
/// names the server is reached by (behind a proxy, the proxy's public name);
/// `*` allows any. Compared without the port, case-insensitively.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct AllowedHosts(Arc<Vec<String>>);

impl AllowedHosts {
    /// The names given, or why one cannot be a host name.
    pub fn new<S: AsRef<str>>(names: &[S]) -> Result<Self, String> {
        let mut hosts = Vec::with_capacity(names.len());
        for name in names {
            let name = name.as_ref().trim().trim_end_matches('.').to_ascii_lowercase();
            let valid = name == "*"
                || (!name.is_empty()
                    && name
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '.' | '_')));
            if !valid {
                return Err(format!(
                    "allowed host {name:?}: a host name without port (letters, digits, '-', '.') or *"
                ));
            }
            hosts.push(name);
        }
        Ok(Self(Arc::new(hosts)))
    }

    /// A request may name `host` (no port).
    fn allows(&self, host: &str) -> bool {
        host.parse::<IpAddr>().is_ok()
            || host == "localhost"
            || host.ends_with(".localhost")
            || self.0.iter().any(|h| h == "*" || h == host)
    }
}

/// Refuses a `POST` that is not JSON (415), names a foreign host (403) or
/// comes from a foreign origin (403).
pub async fn cross_site(State(allowed): State<AllowedHosts>, request: Request, next: Next) -> Response {
    if request.method() == Method::POST
        && let Err(refusal) = check(request.headers(), &allowed)
    {
        return refusal.into_response();
    }
    next.run(request).await
}

fn check(headers: &HeaderMap, allowed: &AllowedHosts) -> Result<(), ApiError> {
    json_media_type(headers.get(header::CONTENT_TYPE))?;
    let forbidden = |field: &str, reason: String| {
        ApiError::new(
            StatusCode::FORBIDDEN,
            "forbidden",
            format!("{field}: {reason}"),
            vec![FieldError::new(field, reason)],
        )
    };
    let host = headers
        .get(header::HOST)
        .and_then(|h| h.to_str().ok())
        .and_then(Authority::parse)
        .ok_or_else(|| forbidden("Host", "missing or not a host[:port]".to_string()))?;
    if !allowed.allows(&host.name) {
        return Err(forbidden(
            "Host",
            format!(
                "{} is not a name this server answers to (an IP address, localhost or `serve --allowed-host`)",
                host.name
            ),
        ));
    }
    let Some(origin) = headers.get(header::ORIGIN) else {
        return Ok(());
    };
    let text = origin.to_str().unwrap_or("");
    let same = text
        .split_once("://")
        .and_then(|(scheme, rest)| Some((scheme.to_ascii_lowercase(), Authority::parse(rest)?)))
        .is_some_and(|(scheme, o)| {
            let default = if scheme == "https" { 443 } else { 80 };
            let own = o.name == host.name && o.port.unwrap_or(default) == host.port.unwrap_or(default);
            own || (o.name.parse::<IpAddr>().is_err() && allowed.0.iter().any(|h| h == "*" || *h == o.name))
        });
    if !same {
        return Err(forbidden(
            "Origin",
            format!("{text:?} is another site: this server takes writes only from its own pages"),
        ));
    }
    Ok(())
}

/// 415 unless the media type is `application/json` (any parameters).
fn json_media_type(content_type: Option<&HeaderValue>) -> Result<(), ApiError> {
    let media = content_type
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .split(';')
        .next()
        .unwrap_or("")
        .trim();
    if media.eq_ignore_ascii_case("application/json") {
        return Ok(());
    }
    let got = if content_type.is_none() {
        "none".to_string()
    } else {
        format!("{media:?}")
    };
    Err(ApiError::new(
        StatusCode::UNSUPPORTED_MEDIA_TYPE,
        "unsupported_media_type",
        format!("Content-Type must be application/json, got {got}"),
        vec![FieldError::new(
            "Content-Type",
            "must be application/json (also for a POST without a body)",
        )],
    ))
}

/// A host and its port as `Host` and `Origin` give them, the name lowercase.
struct Authority {
    name: String,
    port: Option<u16>,
}

impl Authority {
    fn parse(text: &str) -> Option<Self> {
        let text = text.trim();
        let (name, port) = if let Some(rest) = text.strip_prefix('[') {
            let (v6, after) = rest.split_once(']')?;
            (v6, after.strip_prefix(':'))
        } else {
            match text.rsplit_once(':') {
                Some((name, port)) => (name, Some(port)),
                None => (text, None),
            }
        };
        let port = port.map(str::parse).transpose().ok()?;
        let name = name.trim_end_matches('.').to_ascii_lowercase();
        let valid = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '.' | '_' | ':'));
        valid.then_some(Self { name, port })
    }
}

/// Adds the security headers to every answer.
pub async fn security_headers(request: Request, next: Next) -> Response {
    let mut response = next.run(request).await;
    let headers = response.headers_mut();
    for (name, value) in [
        (header::CONTENT_SECURITY_POLICY, CONTENT_SECURITY_POLICY),
        (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
        (header::REFERRER_POLICY, "no-referrer"),
        (header::X_FRAME_OPTIONS, "DENY"),
    ] {
        headers.insert(name, HeaderValue::from_static(value));
    }
    response
}

#[cfg(test)]
mod tests {
    use super::*;

    fn verdict(pairs: &[(&str, &str)], allowed: &[&str]) -> Option<(u16, String)> {
        let mut headers = HeaderMap::new();
        for (k, v) in pairs {
            headers.insert(
                axum::http::HeaderName::from_bytes(k.as_bytes()).unwrap(),
                HeaderValue::from_str(v).unwrap(),
            );
        }
        let allowed = AllowedHosts::new(allowed).unwrap();
        check(&headers, &allowed)
            .err()
            .map(|e| (e.status.as_u16(), e.body.fields[0].field.clone()))
    }

    const JSON: (&str, &str) = ("content-type", "application/json; charset=utf-8");

    #[test]
    fn own_hosts_and_origins_pass() {
        for pairs in [
            vec![JSON, ("host", "127.0.0.1:8080")],
            vec![
                JSON,
                ("host", "127.0.0.1:8080"),
                ("origin", "http://127.0.0.1:8080"),
            ],
            vec![
                JSON,
                ("host", "localhost:8080"),
                ("origin", "http://localhost:8080"),
            ],
            vec![JSON, ("host", "[::1]:8080"), ("origin", "http://[::1]:8080")],
            vec![
                JSON,
                ("host", "app.localhost"),
                ("origin", "http://app.localhost:80"),
            ],
            vec![JSON, ("host", "10.0.0.7")],
        ] {
            assert_eq!(verdict(&pairs, &[]), None, "{pairs:?}");
        }
        let proxied = [
            JSON,
            ("host", "knots.example.org"),
            ("origin", "https://knots.example.org"),
        ];
        assert_eq!(verdict(&proxied, &["Knots.Example.org"]), None);
        assert_eq!(
            verdict(&proxied, &[]),
            Some((403, "Host".to_string())),
            "a name needs --allowed-host"
        );
        assert_eq!(verdict(&proxied, &["*"]), None);
    }

    #[test]
    fn foreign_hosts_origins_and_media_types_are_refused() {
        let host = ("host", "127.0.0.1:8080");
        for (pairs, expected) in [
            (vec![host], (415, "Content-Type")),
            (vec![("content-type", "text/plain"), host], (415, "Content-Type")),
            (
                vec![("content-type", "application/x-www-form-urlencoded"), host],
                (415, "Content-Type"),
            ),
            (vec![JSON, ("host", "evil.example:8080")], (403, "Host")),
            (vec![JSON], (403, "Host")),
            (
                vec![JSON, host, ("origin", "http://evil.example")],
                (403, "Origin"),
            ),
            (vec![JSON, host, ("origin", "null")], (403, "Origin")),
            (
                vec![JSON, host, ("origin", "http://127.0.0.1:9999")],
                (403, "Origin"),
            ),
            (
                vec![JSON, host, ("origin", "https://127.0.0.1:8080.evil.example")],
                (403, "Origin"),
            ),
        ] {
            assert_eq!(
                verdict(&pairs, &["knots.example.org"]),
                Some((expected.0, expected.1.to_string())),
                "{pairs:?}"
            );
        }
        assert!(AllowedHosts::new(&["evil.example:80"]).is_err());
        assert!(AllowedHosts::new(&["a b"]).is_err());
    }
}
