//! The console's HTTP server: the login page, the console page and its WebSocket, all behind the
//! access token but the login page.
//!
//! Without the token every route but `/login` answers 401 and `/ws` refuses the upgrade. The page
//! is one HTML document with its script and style inlined (embedded with `include_str!`), so the
//! browser fetches nothing else; the token travels in the page's URL and the WebSocket's query
//! (`Referrer-Policy: no-referrer` keeps it out of any other request).

use crate::auth;
use crate::hub::Hub;
use crate::operator::Console;
use crate::replay::ReplayLog;
use crate::server_history::LiveHistory;
use axum::Router;
use axum::extract::ws::{WebSocketUpgrade, rejection::WebSocketUpgradeRejection};
use axum::extract::{RawQuery, State};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{Html, IntoResponse, Response};
use axum::routing::get;
use std::net::SocketAddr;
use std::sync::{Arc, OnceLock};

/// Largest message a client may send (bytes); a larger one closes its connection.
pub const MAX_CLIENT_MESSAGE: usize = 64 * 1024;

/// What every request handler shares.
pub struct AppState {
    /// The access token.
    pub token: Arc<str>,
    /// The run's telemetry.
    pub hub: Arc<Hub>,
    /// Authority, phase and the way into the run.
    pub console: Arc<Console>,
    /// The run so far for clients that join late.
    pub history: Arc<LiveHistory>,
    /// The log being replayed, in replay mode.
    pub replay: Option<Arc<ReplayLog>>,
}

impl AppState {
    /// The state of a console serving a live run (or a replay, given its log).
    pub fn new(
        token: Arc<str>,
        hub: Arc<Hub>,
        console: Arc<Console>,
        replay: Option<Arc<ReplayLog>>,
    ) -> Arc<Self> {
        let history = LiveHistory::follow(&hub);
        Arc::new(Self { token, hub, console, history, replay })
    }

    /// Whether a request presents the token.
    fn authorised(&self, headers: &HeaderMap, query: Option<&str>) -> bool {
        let authorization = headers.get(header::AUTHORIZATION).and_then(|v| v.to_str().ok());
        auth::presented_token(authorization, query).is_some_and(|t| auth::same_token(t, &self.token))
    }
}

/// The console's routes: `/login` (open), `/` (the console) and `/ws` (its WebSocket).
pub fn router(state: Arc<AppState>) -> Router {
    Router::new()
        .route("/login", get(login))
        .route("/", get(index))
        .route("/ws", get(websocket))
        .fallback(fallback)
        .with_state(state)
}

const LOGIN_HTML: &str = include_str!("assets/login.html");

/// The console page with its style and scripts inlined.
fn page() -> &'static str {
    static PAGE: OnceLock<String> = OnceLock::new();
    PAGE.get_or_init(|| {
        let script =
            [include_str!("assets/map.js"), include_str!("assets/panels.js"), include_str!("assets/app.js")]
                .join("\n");
        include_str!("assets/index.html")
            .replace("/*STYLE*/", include_str!("assets/console.css"))
            .replace("/*SCRIPT*/", &script)
    })
}

/// Headers of every page: no referrer (the URL holds the token), nothing cached, nothing loaded
/// from elsewhere.
fn page_response(status: StatusCode, body: &'static str) -> Response {
    let mut response = (status, Html(body)).into_response();
    let headers = response.headers_mut();
    headers.insert(header::REFERRER_POLICY, HeaderValue::from_static("no-referrer"));
    headers.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    headers.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(
            "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; img-src data:; connect-src 'self'; form-action 'self'",
        ),
    );
    response
}

fn unauthorized() -> Response {
    let mut response = page_response(StatusCode::UNAUTHORIZED, LOGIN_HTML);
    response.headers_mut().insert(header::WWW_AUTHENTICATE, HeaderValue::from_static("Bearer"));
    response
}

async fn login() -> Response {
    page_response(StatusCode::OK, LOGIN_HTML)
}

async fn index(
    State(state): State<Arc<AppState>>,
    headers: HeaderMap,
    RawQuery(query): RawQuery,
) -> Response {
    if !state.authorised(&headers, query.as_deref()) {
        return unauthorized();
    }
    page_response(StatusCode::OK, page())
}

async fn fallback(
    State(state): State<Arc<AppState>>,
    headers: HeaderMap,
    RawQuery(query): RawQuery,
) -> Response {
    if !state.authorised(&headers, query.as_deref()) {
        return unauthorized();
    }
    (StatusCode::NOT_FOUND, "not found\n").into_response()
}

async fn websocket(
    State(state): State<Arc<AppState>>,
    headers: HeaderMap,
    RawQuery(query): RawQuery,
    upgrade: Result<WebSocketUpgrade, WebSocketUpgradeRejection>,
) -> Response {
    if !state.authorised(&headers, query.as_deref()) {
        return unauthorized();
    }
    match upgrade {
        Ok(upgrade) => upgrade
            .max_message_size(MAX_CLIENT_MESSAGE)
            .max_frame_size(MAX_CLIENT_MESSAGE)
            .on_upgrade(move |socket| crate::server_ws::client(socket, state)),
        Err(rejection) => rejection.into_response(),
    }
}

/// Routers served on their own threads until dropped.
pub struct Server {
    runtime: tokio::runtime::Runtime,
}

impl Server {
    /// A server with no listener yet (two worker threads).
    pub fn new() -> Result<Self, String> {
        let runtime = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .thread_name("console")
            .enable_all()
            .build()
            .map_err(|e| format!("cannot start the console's threads: {e}"))?;
        Ok(Self { runtime })
    }

    /// Serves `router` on `listen`; gives the address bound (port 0 picks a free one).
    pub fn serve(&self, listen: SocketAddr, router: Router) -> Result<SocketAddr, String> {
        let listener =
            std::net::TcpListener::bind(listen).map_err(|e| format!("cannot listen on {listen}: {e}"))?;
        let addr = listener.local_addr().map_err(|e| format!("{listen}: {e}"))?;
        listener.set_nonblocking(true).map_err(|e| format!("{listen}: {e}"))?;
        let _context = self.runtime.enter();
        let listener = tokio::net::TcpListener::from_std(listener).map_err(|e| format!("{listen}: {e}"))?;
        self.runtime.spawn(async move {
            if let Err(e) = axum::serve(listener, router).await {
                eprintln!("error: console server on {addr}: {e}");
            }
        });
        Ok(addr)
    }
}
