//! `umbra explore`'s server: the engine's [`Explorer`] answering GET requests on loopback
//! (axum on tokio). The page, its API and the static export are the engine's
//! (`umbra::study::explore`); only the serving is here, with the server's crates.

use std::sync::Arc;
use umbra::study::explore::{Explorer, Response};
use umbra::{Error, Result};

/// Serves the page on `127.0.0.1:port` (0: any free port) until the process ends, calling
/// `ready` with the address once it listens. Requests are answered on a thread pool, the
/// engine's work off the server's own threads.
pub fn serve(explorer: Explorer, port: u16, ready: impl FnOnce(&str)) -> Result<()> {
    use axum::http::{header, Method, StatusCode, Uri};
    let failed = |what: &str, e: std::io::Error| Error::InvalidOption(format!("{what}: {e}"));
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_io()
        .build()
        .map_err(|e| failed("cannot start the server", e))?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(("127.0.0.1", port))
            .await
            .map_err(|e| failed(&format!("cannot listen on 127.0.0.1:{port}"), e))?;
        let address = listener.local_addr().map_err(|e| failed("the server has no address", e))?;
        ready(&format!("http://{address}/"));
        let explorer = Arc::new(explorer);
        let app = axum::Router::new().fallback(move |method: Method, uri: Uri| {
            let explorer = explorer.clone();
            async move {
                let r = if method == Method::GET {
                    let url = uri.path_and_query().map_or("/", |p| p.as_str()).to_owned();
                    let answer = tokio::task::spawn_blocking(move || explorer.handle(&url)).await;
                    answer.unwrap_or_else(|e| Response::error(500, &format!("the engine failed: {e}")))
                } else {
                    Response::error(405, "only GET is served")
                };
                let status = StatusCode::from_u16(r.status).unwrap_or(StatusCode::INTERNAL_SERVER_ERROR);
                (status, [(header::CONTENT_TYPE, r.content_type)], r.body)
            }
        });
        axum::serve(listener, app).await.map_err(|e| failed("the server stopped", e))
    })
}
